#include "fem/SurfaceCrossing.h"

#include "fem/DisplaySurface.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <unordered_map>

namespace caps::fem {

namespace {

using Triangle = std::array<int, 3>; // welded vertex indices

/// A cell of a uniform grid, hashed.
struct Cell
{
  long long i, j, k;
  bool operator==(const Cell& o) const { return i == o.i && j == o.j && k == o.k; }
};
struct CellHash
{
  std::size_t operator()(const Cell& c) const
  {
    return std::size_t(c.i * 73856093LL ^ c.j * 19349663LL ^ c.k * 83492791LL);
  }
};

Cell cellOf(const Eigen::Vector3d& x, const Eigen::Vector3d& origin, double size)
{
  const Eigen::Vector3d g = (x - origin) / size;
  return {(long long)std::floor(g.x()), (long long)std::floor(g.y()), (long long)std::floor(g.z())};
}

/// The surface's vertices in the deformed position.
Eigen::Matrix3Xd deformedVertices(const DisplaySurface& surface, const Eigen::VectorXd& u)
{
  const std::vector<int>& nodes = surface.displayNodes();
  Eigen::Matrix3Xd nodal(3, Eigen::Index(nodes.size()));
  for (std::size_t i = 0; i < nodes.size(); ++i)
    nodal.col(Eigen::Index(i)) = u.segment<3>(3 * Eigen::Index(nodes[i]));
  return surface.undeformedPositions() + nodal * surface.interpolation();
}

/// Vertex -> its representative: vertices closer than @a tolerance are one.
std::vector<int> weldVertices(const Eigen::Matrix3Xd& x, double tolerance)
{
  std::vector<int> representative(std::size_t(x.cols()));
  std::unordered_map<Cell, std::vector<int>, CellHash> grid;
  const Eigen::Vector3d origin = x.rowwise().minCoeff();
  for (Eigen::Index v = 0; v < x.cols(); ++v)
  {
    const Cell c = cellOf(x.col(v), origin, tolerance);
    int found = -1;
    for (long long di = -1; di <= 1 && found < 0; ++di)
      for (long long dj = -1; dj <= 1 && found < 0; ++dj)
        for (long long dk = -1; dk <= 1 && found < 0; ++dk)
        {
          const auto it = grid.find({c.i + di, c.j + dj, c.k + dk});
          if (it == grid.end())
            continue;
          for (int w : it->second)
            if ((x.col(w) - x.col(v)).norm() <= tolerance)
            {
              found = w;
              break;
            }
        }
    representative[std::size_t(v)] = found >= 0 ? found : int(v);
    if (found < 0)
      grid[c].push_back(int(v));
  }
  return representative;
}

/// Whether segment p..q passes through the interior of triangle (a, b, c)
/// (Möller-Trumbore): strictly inside the segment and the triangle, so
/// touching at an edge or a vertex does not count; @a where the point.
bool segmentCrossesTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& a,
                            const Eigen::Vector3d& b, const Eigen::Vector3d& c, Eigen::Vector3d& where)
{
  constexpr double eps = 1e-9;
  const Eigen::Vector3d d = q - p, e1 = b - a, e2 = c - a;
  const Eigen::Vector3d h = d.cross(e2);
  const double det = e1.dot(h);
  if (std::abs(det) <= eps * d.norm() * e1.norm() * e2.norm()) // parallel or in the plane
    return false;
  const Eigen::Vector3d s = p - a;
  const double beta = s.dot(h) / det;
  const Eigen::Vector3d sq = s.cross(e1);
  const double gamma = d.dot(sq) / det;
  const double t = e2.dot(sq) / det;
  if (beta <= eps || gamma <= eps || beta + gamma >= 1.0 - eps || t <= eps || t >= 1.0 - eps)
    return false;
  where = p + t * d;
  return true;
}

/// Whether triangles @a s and @a t cross: an edge of one through the other.
bool trianglesCross(const Eigen::Matrix3Xd& x, const Triangle& s, const Triangle& t, Eigen::Vector3d& where)
{
  for (int pass = 0; pass < 2; ++pass)
  {
    const Triangle& edges = pass == 0 ? s : t;
    const Triangle& face = pass == 0 ? t : s;
    for (int k = 0; k < 3; ++k)
      if (segmentCrossesTriangle(x.col(edges[std::size_t(k)]), x.col(edges[std::size_t((k + 1) % 3)]), x.col(face[0]),
                                 x.col(face[1]), x.col(face[2]), where))
        return true;
  }
  return false;
}

/// How far triangle @a s reaches through the plane of @a t: the lesser of
/// its vertices' farthest distances on either side.
double reachThrough(const Eigen::Matrix3Xd& x, const Triangle& s, const Triangle& t)
{
  const Eigen::Vector3d a = x.col(t[0]);
  const Eigen::Vector3d n = (x.col(t[1]) - a).cross(x.col(t[2]) - a).normalized();
  double above = 0.0, below = 0.0;
  for (int v : s)
  {
    const double d = n.dot(x.col(v) - a);
    above = std::max(above, d);
    below = std::max(below, -d);
  }
  return std::min(above, below);
}

/// How deep two crossing triangles interpenetrate: the lesser reach of
/// either through the other's plane. Surfaces that slide on each other
/// cross at a sliver of this depth; a flap pushed into its neighbour, or
/// two surfaces crossing at an angle, by the size of their triangles.
double crossingDepth(const Eigen::Matrix3Xd& x, const Triangle& s, const Triangle& t)
{
  return std::min(reachThrough(x, s, t), reachThrough(x, t, s));
}

bool shareVertex(const Triangle& s, const Triangle& t)
{
  for (int a : s)
    for (int b : t)
      if (a == b)
        return true;
  return false;
}

/// The polygons split into triangles on welded vertices; @a faceOf the
/// boundary face each came from.
std::vector<Triangle> weldedTriangles(const DisplaySurface& surface, const std::vector<int>& weld,
                                      std::vector<int>& faceOf)
{
  std::vector<Triangle> triangles;
  for (std::size_t p = 0; p < surface.polygons().size(); ++p)
  {
    const std::vector<int>& polygon = surface.polygons()[p];
    for (std::size_t k = 1; k + 1 < polygon.size(); ++k)
    {
      const Triangle t = {weld[std::size_t(polygon[0])], weld[std::size_t(polygon[k])],
                          weld[std::size_t(polygon[k + 1])]};
      if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) // collapsed where sutured points meet
        continue;
      triangles.push_back(t);
      faceOf.push_back(surface.polygonFace()[p]);
    }
  }
  return triangles;
}

} // namespace

SurfaceCrossingCheck checkSurfaceCrossings(const Mesh& mesh, const std::vector<ElementFace>& faces,
                                           const Eigen::VectorXd& u, double depthTolerance, int resolution,
                                           double weldTolerance)
{
  if (u.size() != 3 * Eigen::Index(mesh.nodeCount()))
    throw std::invalid_argument("surface crossings: " + std::to_string(u.size()) + " displacements for " +
                                std::to_string(mesh.nodeCount()) + " nodes");
  SurfaceCrossingCheck check;
  if (faces.empty())
    return check;
  const DisplaySurface surface(mesh, faces, resolution);
  const Eigen::Matrix3Xd x = deformedVertices(surface, u);
  const double size = (x.rowwise().maxCoeff() - x.rowwise().minCoeff()).norm();
  const std::vector<int> weld = weldVertices(x, std::max(weldTolerance * size, 1e-300));
  std::vector<int> faceOf;
  const std::vector<Triangle> triangles = weldedTriangles(surface, weld, faceOf);
  check.triangles = int(triangles.size());
  check.depthTolerance = depthTolerance;

  // Broad phase: every triangle in the grid cells its bounding box covers,
  // cells about as large as a typical triangle.
  double meanEdge = 0.0;
  for (const Triangle& t : triangles)
    meanEdge += (x.col(t[0]) - x.col(t[1])).norm();
  const double cell = std::max(meanEdge / std::max<std::size_t>(triangles.size(), 1), 1e-12 * size);
  const Eigen::Vector3d origin = x.rowwise().minCoeff();
  std::unordered_map<Cell, std::vector<int>, CellHash> grid;
  std::vector<std::pair<Cell, Cell>> box(triangles.size());
  for (std::size_t i = 0; i < triangles.size(); ++i)
  {
    const Triangle& t = triangles[i];
    Eigen::Vector3d lo = x.col(t[0]), hi = x.col(t[0]);
    for (int k = 1; k < 3; ++k)
    {
      lo = lo.cwiseMin(x.col(t[std::size_t(k)]));
      hi = hi.cwiseMax(x.col(t[std::size_t(k)]));
    }
    box[i] = {cellOf(lo, origin, cell), cellOf(hi, origin, cell)};
    for (long long a = box[i].first.i; a <= box[i].second.i; ++a)
      for (long long b = box[i].first.j; b <= box[i].second.j; ++b)
        for (long long c = box[i].first.k; c <= box[i].second.k; ++c)
          grid[{a, b, c}].push_back(int(i));
  }

  // Narrow phase: each candidate pair once, neighbours skipped.
  std::vector<int> lastTestedWith(triangles.size(), -1);
  for (std::size_t i = 0; i < triangles.size(); ++i)
    for (long long a = box[i].first.i; a <= box[i].second.i; ++a)
      for (long long b = box[i].first.j; b <= box[i].second.j; ++b)
        for (long long c = box[i].first.k; c <= box[i].second.k; ++c)
        {
          const auto cellTriangles = grid.find({a, b, c});
          for (int j : cellTriangles->second)
          {
            if (std::size_t(j) <= i || lastTestedWith[std::size_t(j)] == int(i))
              continue;
            lastTestedWith[std::size_t(j)] = int(i);
            if (shareVertex(triangles[i], triangles[std::size_t(j)]))
              continue;
            Eigen::Vector3d where;
            if (!trianglesCross(x, triangles[i], triangles[std::size_t(j)], where))
              continue;
            const double depth = crossingDepth(x, triangles[i], triangles[std::size_t(j)]);
            if (depth <= check.depthTolerance)
            {
              ++check.shallowPairs;
              continue;
            }
            ++check.crossingPairs;
            if (depth > check.deepest)
            {
              check.deepest = depth;
              check.faceA = faceOf[i];
              check.faceB = faceOf[std::size_t(j)];
              check.where = where;
            }
          }
        }
  return check;
}

} // namespace caps::fem
