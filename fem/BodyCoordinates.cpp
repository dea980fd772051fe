#include "fem/BodyCoordinates.h"

#include <Eigen/LU>
#include <Eigen/QR>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace caps::fem {

namespace {

/// How far @a rst lies outside the natural domain of @a kind: <= 0 inside.
/// Brick: max |r|, |s|, |t| less 1. Wedge (r, s >= 0, r + s <= 1, |t| <= 1):
/// the triangle's violations doubled, as its (r, s) span half the brick's.
double outside(ElementKind kind, const Eigen::Vector3d& rst)
{
  if (kind == ElementKind::Wedge15)
    return std::max({-2.0 * rst[0], -2.0 * rst[1], 2.0 * (rst[0] + rst[1] - 1.0), std::abs(rst[2]) - 1.0});
  return rst.cwiseAbs().maxCoeff() - 1.0;
}

/// The nearest point of the natural domain (for points within round-off of it).
Eigen::Vector3d clampInto(ElementKind kind, Eigen::Vector3d rst)
{
  rst[2] = std::clamp(rst[2], -1.0, 1.0);
  if (kind == ElementKind::Wedge15)
  {
    rst[0] = std::max(rst[0], 0.0);
    rst[1] = std::max(rst[1], 0.0);
    if (rst[0] + rst[1] > 1.0)
      rst.head<2>() /= rst[0] + rst[1];
    return rst;
  }
  return rst.cwiseMax(-1.0).cwiseMin(1.0);
}

void checkBodyPoint(const Mesh& mesh, const BodyPoint& p)
{
  if (p.element < 0 || std::size_t(p.element) >= mesh.elements.size())
    throw std::invalid_argument("body point in element " + std::to_string(p.element) + ", but the mesh has " +
                                std::to_string(mesh.elements.size()) + " elements");
  const ElementKind kind = mesh.elements[std::size_t(p.element)].kind;
  if (!p.rst.allFinite() || outside(kind, p.rst) > BodyCoordinateLocator::kNaturalTolerance)
  {
    std::ostringstream m;
    m << "body point (" << p.element << ", " << p.rst[0] << ", " << p.rst[1] << ", " << p.rst[2]
      << ") lies outside its element: "
      << (kind == ElementKind::Wedge15 ? "a wedge needs r, s >= 0, r + s <= 1 and t in [-1, 1]"
                                       : "r, s, t must be in [-1, 1]");
    throw std::invalid_argument(m.str());
  }
}

ShapeVector shapeValues(const Mesh& mesh, const BodyPoint& p)
{
  checkBodyPoint(mesh, p);
  const Element& el = mesh.elements[std::size_t(p.element)];
  ShapeVector h;
  ElementShape::fromConnectivity(el.kind, el.nodes).values(p.rst, h);
  return h;
}

/// Nodal displacements of element @a e in Bathe order (absent rows zero).
ElementCoordinates elementDisplacements(const Mesh& mesh, const Eigen::VectorXd& u, std::size_t e)
{
  if (u.size() != mesh.dofCount())
    throw std::invalid_argument("the displacement vector has " + std::to_string(u.size()) +
                                " entries; the mesh needs 3 per node (" + std::to_string(mesh.dofCount()) + ")");
  ElementCoordinates d;
  const Element& el = mesh.elements[e];
  for (int k = 0; k < kHex20NodeCount; ++k)
  {
    if (el.nodes[k] >= 0)
      d.row(k) = u.segment<3>(3 * Eigen::Index(el.nodes[k])).transpose();
    else
      d.row(k).setZero();
  }
  return d;
}

// The 5 x 5 x 5 sample grid used for boxes and starts: over [-1, 1]^3 for a
// brick, over the square [0, 1]^2 x [-1, 1] holding a wedge's triangle.
constexpr int kSamples = 5;
Eigen::Vector3d samplePoint(ElementKind kind, int i, int j, int k)
{
  const double lo = kind == ElementKind::Wedge15 ? 0.0 : -1.0;
  const double step = (1.0 - lo) / (kSamples - 1);
  return Eigen::Vector3d(lo + step * i, lo + step * j, -1.0 + 2.0 * k / (kSamples - 1));
}

// Newton starts, all strictly inside the element so none sits on a
// collapsed edge (singular Jacobian) of a degenerate wedge: the centres of
// the 3 x 3 x 3 sub-cells of a brick, four points of the triangle times
// three levels of t for a native wedge.
const std::vector<Eigen::Vector3d>& startPoints(ElementKind kind)
{
  static const std::vector<Eigen::Vector3d> brick = [] {
    std::vector<Eigen::Vector3d> p;
    for (double r : {-2.0 / 3, 0.0, 2.0 / 3})
      for (double s : {-2.0 / 3, 0.0, 2.0 / 3})
        for (double t : {-2.0 / 3, 0.0, 2.0 / 3})
          p.emplace_back(r, s, t);
    return p;
  }();
  static const std::vector<Eigen::Vector3d> wedge = [] {
    std::vector<Eigen::Vector3d> p;
    for (double t : {-2.0 / 3, 0.0, 2.0 / 3})
      for (const auto& [r, s] :
           {std::pair{1.0 / 6, 1.0 / 6}, {2.0 / 3, 1.0 / 6}, {1.0 / 6, 2.0 / 3}, {1.0 / 3, 1.0 / 3}})
        p.emplace_back(r, s, t);
    return p;
  }();
  return kind == ElementKind::Wedge15 ? wedge : brick;
}

} // namespace

Eigen::Vector3d worldPoint(const Mesh& mesh, const BodyPoint& p)
{
  const ShapeVector h = shapeValues(mesh, p);
  return mesh.elementCoordinates(std::size_t(p.element)).transpose() * h; // eq. 4.13
}

Eigen::Vector3d displacementAt(const Mesh& mesh, const Eigen::VectorXd& u, const BodyPoint& p)
{
  const ShapeVector h = shapeValues(mesh, p);
  return elementDisplacements(mesh, u, std::size_t(p.element)).transpose() * h; // eq. 4.14
}

Eigen::Vector3d displacedWorldPoint(const Mesh& mesh, const Eigen::VectorXd& u, const BodyPoint& p)
{
  const ShapeVector h = shapeValues(mesh, p);
  const std::size_t e = std::size_t(p.element);
  return (mesh.elementCoordinates(e) + elementDisplacements(mesh, u, e)).transpose() * h; // eq. 4.15
}

BodyCoordinateLocator::BodyCoordinateLocator(const Mesh& mesh)
{
  const Eigen::Index n = mesh.nodeCount();
  for (Eigen::Index i = 0; i < n; ++i)
    if (!mesh.nodes.col(i).allFinite())
      throw std::invalid_argument("node " + std::to_string(i) + " has a non-finite coordinate");
  const std::size_t ne = mesh.elements.size();
  kinds_.reserve(ne);
  shapes_.reserve(ne);
  coordinates_.reserve(ne);
  starts_.reserve(ne);
  boxMin_.resize(ne);
  boxMax_.resize(ne);
  size_.resize(ne);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(HUGE_VAL), hi = -lo;
  double sizeSum = 0.0;
  ShapeVector h;
  for (std::size_t e = 0; e < ne; ++e)
  {
    const Element& el = mesh.elements[e];
    const bool wedge = el.kind == ElementKind::Wedge15;
    for (int k = 0; k < kHex20NodeCount; ++k)
    {
      const bool required = k < (wedge ? kWedge15NodeCount : kHex20CornerCount);
      const bool unused = wedge && k >= kWedge15NodeCount;
      if (el.nodes[k] >= n || el.nodes[k] < -1 || (el.nodes[k] < 0 && required) || (unused && el.nodes[k] != -1))
        throw std::invalid_argument("element " + std::to_string(e) + ": local node " + std::to_string(k) +
                                    " refers to node " + std::to_string(el.nodes[k]) + ", but the mesh has nodes 0.." +
                                    std::to_string(n - 1) + (wedge ? " (a native wedge uses slots 0..14)" : ""));
    }
    kinds_.push_back(el.kind);
    shapes_.push_back(ElementShape::fromConnectivity(el.kind, el.nodes));
    coordinates_.push_back(mesh.elementCoordinates(e));
    const ElementCoordinates& x = coordinates_.back();

    Eigen::Vector3d samples[kSamples][kSamples][kSamples];
    Eigen::Vector3d bmin = Eigen::Vector3d::Constant(HUGE_VAL), bmax = -bmin;
    for (int i = 0; i < kSamples; ++i)
      for (int j = 0; j < kSamples; ++j)
        for (int k = 0; k < kSamples; ++k)
        {
          shapes_.back().values(samplePoint(el.kind, i, j, k), h);
          samples[i][j][k] = x.transpose() * h;
          bmin = bmin.cwiseMin(samples[i][j][k]);
          bmax = bmax.cwiseMax(samples[i][j][k]);
        }
    // x is at most quadratic along each natural axis (brick and wedge), so a
    // second difference is exact, and the mapping strays from the
    // (box-bounded) multilinear interpolant of the samples by at most 1/8 of
    // the summed maxima.
    Eigen::Vector3d bend = Eigen::Vector3d::Zero();
    for (int axis = 0; axis < 3; ++axis)
    {
      Eigen::Vector3d maxSecond = Eigen::Vector3d::Zero();
      for (int i = 0; i < kSamples; ++i)
        for (int j = 0; j < kSamples; ++j)
          for (int k = 1; k + 1 < kSamples; ++k)
          {
            auto at = [&](int m) -> const Eigen::Vector3d& {
              return axis == 0 ? samples[m][i][j] : axis == 1 ? samples[i][m][j] : samples[i][j][m];
            };
            maxSecond = maxSecond.cwiseMax((at(k + 1) - 2.0 * at(k) + at(k - 1)).cwiseAbs());
          }
      bend += maxSecond / 8.0;
    }
    const std::vector<Eigen::Vector3d>& starts = startPoints(el.kind);
    starts_.emplace_back(3, Eigen::Index(starts.size()));
    for (std::size_t i = 0; i < starts.size(); ++i)
    {
      shapes_.back().values(starts[i], h);
      starts_.back().col(Eigen::Index(i)) = x.transpose() * h;
    }
    const double diagonal = (bmax - bmin).norm();
    // Round-off slack so points on a flat face are not lost.
    const Eigen::Vector3d grow = bend + Eigen::Vector3d::Constant(1e-9 * diagonal);
    boxMin_[e] = bmin - grow;
    boxMax_[e] = bmax + grow;
    size_[e] = diagonal;
    sizeSum += diagonal;
    lo = lo.cwiseMin(boxMin_[e]);
    hi = hi.cwiseMax(boxMax_[e]);
  }
  if (ne == 0)
    return;

  // About one cell per element of the mean size, at most 8 cells per element.
  const Eigen::Vector3d extent = (hi - lo).cwiseMax(1e-12);
  const double target = std::max(sizeSum / double(ne) / std::sqrt(3.0), 1e-12);
  Eigen::Vector3d count = (extent / target).array().ceil().max(1.0).matrix();
  const double cap = 8.0 * double(ne);
  if (count.prod() > cap)
    count = (count * std::cbrt(cap / count.prod())).array().ceil().max(1.0).matrix();
  cells_ = count.cast<int>();
  gridMin_ = lo;
  cell_ = extent.cwiseQuotient(count);
  bins_.assign(std::size_t(cells_.prod()), {});
  for (std::size_t e = 0; e < ne; ++e)
  {
    Eigen::Vector3i a, b;
    for (int d = 0; d < 3; ++d)
    {
      a[d] = std::clamp(int(std::floor((boxMin_[e][d] - lo[d]) / cell_[d])), 0, cells_[d] - 1);
      b[d] = std::clamp(int(std::floor((boxMax_[e][d] - lo[d]) / cell_[d])), 0, cells_[d] - 1);
    }
    for (int i = a[0]; i <= b[0]; ++i)
      for (int j = a[1]; j <= b[1]; ++j)
        for (int k = a[2]; k <= b[2]; ++k)
          bins_[std::size_t((k * cells_[1] + j) * cells_[0] + i)].push_back(int(e));
  }
}

std::vector<int> BodyCoordinateLocator::candidates(const Eigen::Vector3d& world) const
{
  std::vector<int> out;
  if (bins_.empty() || !world.allFinite())
    return out;
  Eigen::Vector3i c;
  for (int d = 0; d < 3; ++d)
  {
    const double f = std::floor((world[d] - gridMin_[d]) / cell_[d]);
    if (f < -1.0 || f > double(cells_[d]))
      return out; // well outside every box
    c[d] = std::clamp(int(f), 0, cells_[d] - 1);
  }
  for (int e : bins_[std::size_t((c[2] * cells_[1] + c[1]) * cells_[0] + c[0])])
  {
    const std::size_t i = std::size_t(e);
    if ((world.array() >= boxMin_[i].array()).all() && (world.array() <= boxMax_[i].array()).all())
      out.push_back(e);
  }
  return out;
}

BodyCoordinateLocator::Candidate BodyCoordinateLocator::newton(std::size_t e, const Eigen::Vector3d& world) const
{
  const ElementShape& shape = shapes_[e];
  const ElementKind kind = kinds_[e];
  const ElementCoordinates& x = coordinates_[e];
  Candidate c;
  c.point.element = int(e);

  // Start from the nearest of the element's start points.
  Eigen::Index nearest = 0;
  (starts_[e].colwise() - world).colwise().squaredNorm().minCoeff(&nearest);
  Eigen::Vector3d rst = startPoints(kind)[std::size_t(nearest)];

  const double tolerance = 1e-13 * std::max(size_[e], 1e-300);
  PointGeometry g;
  evaluateGeometry(shape, x, rst, int(e), g, false);
  Eigen::Vector3d residual = g.world - world;
  for (int iteration = 0; iteration < 60 && residual.norm() > tolerance; ++iteration)
  {
    // dx/d(r,s,t) is J^T (J(i, j) = dx_j / dr_i); least squares where it is
    // singular, e.g. on the collapsed edge of a wedge.
    const Eigen::Matrix3d dxdr = g.jacobian.transpose();
    Eigen::Vector3d step;
    const Eigen::FullPivLU<Eigen::Matrix3d> lu(dxdr);
    if (lu.isInvertible() && std::abs(g.detJ) > 1e-12 * std::pow(g.jacobian.norm(), 3))
      step = -lu.solve(residual);
    else
      step = -dxdr.completeOrthogonalDecomposition().solve(residual);
    // Damped: halve the step until the residual falls.
    double lambda = 1.0;
    PointGeometry trial;
    bool improved = false;
    for (int halving = 0; halving < 30; ++halving, lambda *= 0.5)
    {
      evaluateGeometry(shape, x, rst + lambda * step, int(e), trial, false);
      if ((trial.world - world).norm() < residual.norm())
      {
        improved = true;
        break;
      }
    }
    if (!improved)
      break;
    rst += lambda * step;
    g = trial;
    residual = g.world - world;
    // Far outside the element: the point is not in it.
    if (outside(kind, rst) > 2.0)
      break;
  }
  c.point.rst = rst;
  c.residual = residual.norm();
  c.outside = outside(kind, rst);
  // Converged in place (to round-off of the element's size).
  c.converged = c.residual <= 1e-10 * std::max(size_[e], 1e-300);
  return c;
}

std::optional<BodyPoint> BodyCoordinateLocator::find(const Eigen::Vector3d& world) const
{
  std::optional<Candidate> best;
  for (int e : candidates(world))
  {
    const Candidate c = newton(std::size_t(e), world);
    if (!c.converged || c.outside > kNaturalTolerance)
      continue;
    if (!best || c.outside < best->outside)
      best = c;
  }
  if (!best)
    return std::nullopt;
  BodyPoint p = best->point;
  p.rst = clampInto(kinds_[std::size_t(p.element)], p.rst);
  return p;
}

BodyPoint BodyCoordinateLocator::locate(const Eigen::Vector3d& world) const
{
  if (auto p = find(world))
    return *p;
  std::ostringstream m;
  m << "the point (" << world[0] << ", " << world[1] << ", " << world[2] << ") mm lies outside the mesh";
  // Name the element it came closest to, if any box held it.
  std::optional<Candidate> nearest;
  for (int e : candidates(world))
  {
    Candidate c = newton(std::size_t(e), world);
    // Distance to the element: clamp into it and measure.
    ShapeVector h;
    shapes_[std::size_t(e)].values(clampInto(kinds_[std::size_t(e)], c.point.rst), h);
    c.residual = (coordinates_[std::size_t(e)].transpose() * h - world).norm();
    if (!nearest || c.residual < nearest->residual)
      nearest = c;
  }
  if (nearest)
    m << " (about " << nearest->residual << " mm from element " << nearest->point.element << ")";
  else
    m << " (beyond the bounding box of every element)";
  throw std::out_of_range(m.str());
}

} // namespace caps::fem
