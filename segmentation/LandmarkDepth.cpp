#include "segmentation/LandmarkDepth.h"

#include "segmentation/RangeMapImageGeometry.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <Eigen/QR>
#include <vtkImageData.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace caps::seg {

namespace {

constexpr double kAirHu = -1000.0;

/// The normal of the plane through @a points (total least squares), on the
/// side of @a towards.
Eigen::Vector3d planeNormal(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& towards)
{
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& q : points)
    mean += q;
  mean /= double(points.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const auto& q : points)
    scatter += (q - mean) * (q - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(scatter);
  const Eigen::Vector3d fitted = eig.eigenvectors().col(0);
  return fitted.dot(towards) < 0.0 ? Eigen::Vector3d(-fitted) : fitted;
}

/// The normal at @a at of the polynomial height function h(u, v) fitted by
/// least squares to @a points over the plane through @a at spanned by @a t1,
/// @a t2 (heights along @a n): an osculating jet (Cazals and Pouget 2005,
/// "Estimating differential quantities using polynomial fitting of
/// osculating jets"). On a grid symmetric about the point a jet of degree d
/// gives a slope exact on any patch of degree d + 1, where the plane through
/// the points of a curved patch (total least squares) leans with the
/// curvature and its change: by 5 degrees 1 mm beside the apex of a lip,
/// over +-2 mm. Degree 3 with 40 points or more (its slope noise over 7 x 7
/// crossings is a plane's over 5 x 5), 2 with 12, else the plane. A point
/// more than 0.5 mm off the fit is the crossing of another surface (the ala
/// beside the cheek): the worst is left out and the jet fitted again.
Eigen::Vector3d jetNormal(std::vector<Eigen::Vector3d> points, const Eigen::Vector3d& at, const Eigen::Vector3d& n,
                          const Eigen::Vector3d& t1, const Eigen::Vector3d& t2)
{
  constexpr double kOffTheSkin = 0.5; // mm
  const std::size_t kept = points.size() / 2;
  while (points.size() >= 12)
  {
    const int terms = points.size() >= 40 ? 10 : 6;
    Eigen::MatrixXd design(points.size(), terms);
    Eigen::VectorXd height(points.size());
    for (std::size_t k = 0; k < points.size(); ++k)
    {
      const Eigen::Vector3d d = points[k] - at;
      const double u = d.dot(t1), v = d.dot(t2);
      const double row[10] = {1.0, u, v, u * u, u * v, v * v, u * u * u, u * u * v, u * v * v, v * v * v};
      for (int c = 0; c < terms; ++c)
        design(Eigen::Index(k), c) = row[c];
      height(Eigen::Index(k)) = d.dot(n);
    }
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(design);
    if (qr.rank() < terms)
      break;
    const Eigen::VectorXd c = qr.solve(height);
    Eigen::Index worst = 0;
    const double worstResidual = (design * c - height).cwiseAbs().maxCoeff(&worst);
    if (worstResidual <= kOffTheSkin || points.size() <= kept)
      return (n - c(1) * t1 - c(2) * t2).normalized();
    points.erase(points.begin() + worst);
  }
  return planeNormal(points, n);
}

} // namespace

const char* conventionName(DepthConvention convention)
{
  switch (convention)
  {
  case DepthConvention::SkinNormal:
    return "perpendicular to the skin";
  case DepthConvention::NearestBone:
    return "to the nearest bone";
  case DepthConvention::NotADepth:
    return "not a bone depth";
  }
  return "";
}

DepthConvention depthConventionOf(const std::string& landmarkName)
{
  // The nose tip has cartilage beneath it: the tables give no depth there.
  if (landmarkName == "pronasale")
    return DepthConvention::NotADepth;
  // Under the chin and at the jaw's angle the skin normal runs along the
  // bone's curved edge rather than into it; the CT studies measure these to
  // the bony landmark, the nearest bone.
  // At the rhinion the bone ends: the line perpendicular to the skin meets
  // its edge or passes it, and the CT studies measure to the bone's end.
  // At the orbits' rims likewise: the skin normal there passes over the
  // rim's edge into the orbit (on the sample CT 36-39 mm below the lower
  // lid against 7-8 mm to the rim).
  if (landmarkName == "menton" || landmarkName == "gonion_left" || landmarkName == "gonion_right" ||
      landmarkName == "rhinion" || landmarkName.starts_with("supraorbital") || landmarkName.starts_with("infraorbital"))
    return DepthConvention::NearestBone;
  return DepthConvention::SkinNormal;
}

CtSampler::CtSampler(vtkImageData* ct) : ct_(ct)
{
  if (!ct || ct->GetNumberOfScalarComponents() != 1 || !ct->GetScalarPointer())
    throw std::invalid_argument("The landmark depths need a CT with one value per voxel.");
  geometry_ = ImageGeometry::of(ct);
  dims_ = geometry_.dimensions();
  if (dims_[0] < 2 || dims_[1] < 2 || dims_[2] < 2)
    throw std::invalid_argument("The CT must have at least two voxels along each axis.");
}

Eigen::Vector3d CtSampler::indexOf(const Eigen::Vector3d& world) const
{
  const Eigen::Vector3d start(geometry_.extent[0], geometry_.extent[2], geometry_.extent[4]);
  return geometry_.worldToIndex(world) - start;
}

Eigen::Vector3d CtSampler::worldOf(const Eigen::Vector3d& index) const
{
  const Eigen::Vector3d start(geometry_.extent[0], geometry_.extent[2], geometry_.extent[4]);
  return geometry_.indexToWorld(index + start);
}

double CtSampler::huAtIndex(const Eigen::Vector3d& index) const
{
  const double x = index.x(), y = index.y(), z = index.z();
  if (!(x >= 0.0 && y >= 0.0 && z >= 0.0 && x <= dims_[0] - 1 && y <= dims_[1] - 1 && z <= dims_[2] - 1))
    return kAirHu;
  const int i = std::min(int(x), dims_[0] - 2), j = std::min(int(y), dims_[1] - 2), k = std::min(int(z), dims_[2] - 2);
  const double fx = x - i, fy = y - j, fz = z - k;
  // GetScalarComponentAsDouble takes indices in the extent's own numbering.
  auto v = [&](int a, int b, int c) {
    return ct_->GetScalarComponentAsDouble(geometry_.extent[0] + i + a, geometry_.extent[2] + j + b,
                                           geometry_.extent[4] + k + c, 0);
  };
  const double c00 = v(0, 0, 0) + fx * (v(1, 0, 0) - v(0, 0, 0));
  const double c10 = v(0, 1, 0) + fx * (v(1, 1, 0) - v(0, 1, 0));
  const double c01 = v(0, 0, 1) + fx * (v(1, 0, 1) - v(0, 0, 1));
  const double c11 = v(0, 1, 1) + fx * (v(1, 1, 1) - v(0, 1, 1));
  const double c0 = c00 + fy * (c10 - c00), c1 = c01 + fy * (c11 - c01);
  return c0 + fz * (c1 - c0);
}

double CtSampler::hu(const Eigen::Vector3d& world) const
{
  return huAtIndex(indexOf(world));
}

bool skinAgainstAnObject(const CtSampler& ct, const Eigen::Vector3d& skinPoint, const Eigen::Vector3d& outward,
                         double skinThresholdHu)
{
  return ct.hu(skinPoint + 1.5 * outward) >= skinThresholdHu && ct.hu(skinPoint + 3.0 * outward) >= skinThresholdHu;
}

BoneDepthProbe::BoneDepthProbe(vtkImageData* ct, vtkImageData* boneMask, double boneThresholdHu, double skinThresholdHu,
                               double searchDistance)
  : ct_(ct), mask_(nullptr), threshold_(boneThresholdHu), skinThreshold_(skinThresholdHu),
    searchDistance_(searchDistance)
{
  if (!boneMask || boneMask->GetScalarType() != VTK_UNSIGNED_CHAR || boneMask->GetNumberOfScalarComponents() != 1 ||
      !boneMask->GetScalarPointer())
    throw std::invalid_argument("The landmark depths need the bone mask (unsigned char, one value per voxel).");
  if (!ImageGeometry::of(boneMask).sameGrid(ct_.geometry()))
    throw std::invalid_argument("The bone mask is not on the CT's grid.");
  if (!(searchDistance > 0.0))
    throw std::invalid_argument("The bone search distance must be positive.");
  mask_ = static_cast<const unsigned char*>(boneMask->GetScalarPointer());
}

bool BoneDepthProbe::inMask(int i, int j, int k) const
{
  if (i < 0 || j < 0 || k < 0 || i >= ct_.dimensions()[0] || j >= ct_.dimensions()[1] || k >= ct_.dimensions()[2])
    return false;
  return mask_[i + ct_.dimensions()[0] * (j + std::ptrdiff_t(ct_.dimensions()[1]) * k)] != 0;
}

bool BoneDepthProbe::inMask(const Eigen::Vector3d& index) const
{
  return inMask(int(std::lround(index.x())), int(std::lround(index.y())), int(std::lround(index.z())));
}

bool BoneDepthProbe::maskTouches(const Eigen::Vector3d& index) const
{
  const int i0 = int(std::floor(index.x())), j0 = int(std::floor(index.y())), k0 = int(std::floor(index.z()));
  for (int k = k0; k <= k0 + 1; ++k)
    for (int j = j0; j <= j0 + 1; ++j)
      for (int i = i0; i <= i0 + 1; ++i)
        if (inMask(i, j, k))
          return true;
  return false;
}

bool BoneDepthProbe::goesIntoBone(const Eigen::Vector3d& world, const Eigen::Vector3d& direction) const
{
  const double h = 0.5 * ct_.geometry().spacing.maxCoeff();
  Eigen::Vector3d gradient;
  for (int a = 0; a < 3; ++a)
  {
    const Eigen::Vector3d e = h * Eigen::Vector3d::Unit(a);
    gradient[a] = hu(world + e) - hu(world - e);
  }
  return gradient.dot(direction) >= 0.5 * gradient.norm() * direction.norm() && gradient.norm() > 0.0;
}

double BoneDepthProbe::alongRay(const Eigen::Vector3d& from, const Eigen::Vector3d& direction,
                                Eigen::Vector3d* hit) const
{
  const double step = 0.25 * ct_.geometry().spacing.minCoeff();
  const Eigen::Vector3d d = direction.normalized();
  auto index = [&](double t) { return indexOf(from + t * d); };
  auto isBone = [&](double t) { return huAtIndex(index(t)) >= threshold_; };
  if (isBone(0.0) && inMask(index(0.0)))
  {
    if (hit)
      *hit = from;
    return 0.0;
  }
  // March to the first rise of the HU through the threshold next to the
  // bone mask (refined by bisection: the sub-voxel place); the mask's islands
  // and holes are the segmentation's decision, so bright tissue it left out
  // (metal, contrast) is passed through. A thin wall (the maxillary sinus's,
  // under a millimetre) is in the mask but its HU between the voxel centres
  // stays under the threshold: where the line comes within a voxel of the
  // mask, going into it, without a rise within two voxels, the edge of the
  // first mask voxel it enters is taken (to half a voxel), as the range maps
  // do. Going into it: within 60 degrees of the HU's gradient there. A line
  // passing along a bone just outside it (under the chin, grazing the
  // mandible's lower edge) goes on.
  auto bisect = [&](double outside, double inside, auto&& in) {
    for (int it = 0; it < 30; ++it)
    {
      const double mid = 0.5 * (outside + inside);
      (in(mid) ? inside : outside) = mid;
    }
    return 0.5 * (outside + inside);
  };
  auto found = [&](double t) {
    if (hit)
      *hit = from + t * d;
    return t;
  };
  const double window = 2.0 * ct_.geometry().spacing.maxCoeff();
  double previous = 0.0;
  bool wasBone = isBone(0.0);
  for (double t = step; t <= searchDistance_; t += step)
  {
    const bool bone = isBone(t);
    if (bone && !wasBone)
    {
      const double crossing = bisect(previous, t, isBone);
      if (maskTouches(index(crossing + 2.0 * step)))
        return found(crossing);
    }
    else if (maskTouches(index(t)) && goesIntoBone(from + t * d, d))
    {
      // Within two voxels: a HU rise, else the first voxel of the mask
      // itself (its edge between voxel centres), else this place.
      bool before = bone;
      double intoMask = -1.0;
      for (double u = t + step; u <= t + window; u += step)
      {
        const bool now = isBone(u);
        if (now && !before)
          return found(bisect(u - step, u, isBone));
        before = now;
        if (intoMask < 0.0 && inMask(index(u)))
          intoMask = u;
      }
      if (intoMask > 0.0)
        return found(bisect(intoMask - step, intoMask, [&](double v) { return inMask(index(v)); }));
      return found(bisect(previous, t, [&](double v) { return maskTouches(index(v)); }));
    }
    wasBone = bone;
    previous = t;
  }
  return RangeMap::quietNaN();
}

double BoneDepthProbe::toNearest(const Eigen::Vector3d& from, double radius, Eigen::Vector3d* hit) const
{
  radius = std::min(radius, searchDistance_);
  if (!(radius > 0.0) || !from.allFinite())
    return RangeMap::quietNaN();
  // The box of voxels a sphere of the radius reaches: along index axis a,
  // radius times the norm of row a of the world-to-index map.
  const Eigen::Matrix3d toIndex = ct_.geometry().indexToWorldMatrix().inverse();
  const Eigen::Vector3d centre = indexOf(from);
  int lo[3], hi[3];
  for (int a = 0; a < 3; ++a)
  {
    const double reach = radius * toIndex.row(a).norm() + 1.0;
    lo[a] = std::max(0, int(std::floor(centre[a] - reach)));
    hi[a] = std::min(ct_.dimensions()[a] - 1, int(std::ceil(centre[a] + reach)));
  }
  const double voxelDiagonal = ct_.geometry().spacing.norm();
  // The bone surface: on each voxel edge from a voxel of the bone mask to
  // one outside it, where the HU (linear between the two) falls through the
  // threshold; the edge's middle where it does not (a mask edge without a
  // HU edge).
  double best = radius;
  bool found = false;
  Eigen::Vector3d bestPoint;
  constexpr int kOffsets[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (int k = lo[2]; k <= hi[2]; ++k)
    for (int j = lo[1]; j <= hi[1]; ++j)
      for (int i = lo[0]; i <= hi[0]; ++i)
      {
        if (!inMask(i, j, k))
          continue;
        const Eigen::Vector3d inside(i, j, k);
        if ((worldOf(inside) - from).norm() > best + voxelDiagonal)
          continue;
        for (const auto& o : kOffsets)
        {
          const int a = i + o[0], b = j + o[1], c = k + o[2];
          if (a < 0 || b < 0 || c < 0 || a >= ct_.dimensions()[0] || b >= ct_.dimensions()[1] ||
              c >= ct_.dimensions()[2] || inMask(a, b, c))
            continue;
          const Eigen::Vector3d outside(a, b, c);
          const double vIn = huAtIndex(inside), vOut = huAtIndex(outside);
          const double s = vIn >= threshold_ && vOut < threshold_ ? (vIn - threshold_) / (vIn - vOut) : 0.5;
          const Eigen::Vector3d point = worldOf(inside + s * (outside - inside));
          const double distance = (point - from).norm();
          if (distance <= best)
          {
            best = distance;
            bestPoint = point;
            found = true;
          }
        }
      }
  if (!found)
    return RangeMap::quietNaN();
  if (hit)
    *hit = bestPoint;
  return best;
}

Eigen::Vector3d BoneDepthProbe::skinNormal(const Eigen::Vector3d& skinPoint) const
{
  const Eigen::Vector3d none = Eigen::Vector3d::Constant(RangeMap::quietNaN());
  // A first guess: the HU gradient (HU rises from air into tissue, so it
  // points inward), fitted by least squares on a 5 x 5 x 5 stencil of half
  // voxels.
  const double h = 0.5 * ct_.geometry().spacing.maxCoeff();
  Eigen::Matrix3d normalMatrix = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (int a = -2; a <= 2; ++a)
    for (int b = -2; b <= 2; ++b)
      for (int c = -2; c <= 2; ++c)
      {
        const Eigen::Vector3d offset = h * Eigen::Vector3d(a, b, c);
        normalMatrix += offset * offset.transpose();
        rhs += offset * hu(skinPoint + offset); // the stencil is symmetric: the mean drops out
      }
  Eigen::Vector3d normal = normalMatrix.ldlt().solve(rhs);
  if (!(normal.norm() > 0.0))
    return none;
  normal.normalize();
  // Then the skin itself: the skin crossings on a 7 x 7 grid of lines along
  // the normal (+-3 mm around the point) and the jet fitted to them, twice.
  // A gradient of a partial-volume ramp sampled on thick slices leans by a
  // few degrees towards the grid; the crossings lie on the surface.
  constexpr double kSpacing = 1.0, kReach = 4.0, kStep = 0.1;
  for (int pass = 0; pass < 2; ++pass)
  {
    const Eigen::Vector3d t1 = normal.unitOrthogonal(), t2 = normal.cross(t1);
    std::vector<Eigen::Vector3d> points;
    for (int a = -3; a <= 3; ++a)
      for (int b = -3; b <= 3; ++b)
      {
        const Eigen::Vector3d base = skinPoint + kSpacing * (a * t1 + b * t2);
        auto inside = [&](double t) { return hu(base + t * normal) >= skinThreshold_; };
        for (double t = -kReach; t < kReach; t += kStep)
          if (!inside(t) && inside(t + kStep))
          {
            double out = t, in = t + kStep;
            for (int it = 0; it < 20; ++it)
            {
              const double mid = 0.5 * (out + in);
              (inside(mid) ? in : out) = mid;
            }
            points.push_back(base + 0.5 * (out + in) * normal);
            break;
          }
      }
    if (points.size() < 9)
      break; // too little skin around the point: keep the gradient's normal
    normal = jetNormal(points, skinPoint, normal, t1, t2);
  }
  return normal;
}

Eigen::Vector3d BoneDepthProbe::ontoSkin(const Eigen::Vector3d& point, const Eigen::Vector3d& inwardNormal) const
{
  // The skin crossing (air to tissue, walking inward) on the line through
  // the point along the normal nearest the point, within 4 mm.
  constexpr double kReach = 4.0;
  const double step = 0.1 * ct_.geometry().spacing.minCoeff();
  auto inside = [&](double t) { return hu(point + t * inwardNormal) >= skinThreshold_; };
  auto crossingIn = [&](double a, double b) -> double {
    if (inside(a) || !inside(b))
      return RangeMap::quietNaN();
    for (int it = 0; it < 30; ++it)
    {
      const double mid = 0.5 * (a + b);
      (inside(mid) ? b : a) = mid;
    }
    return 0.5 * (a + b);
  };
  for (double s = 0.0; s < kReach; s += step)
  {
    for (const double t : {crossingIn(s, s + step), crossingIn(-s - step, -s)})
      if (std::isfinite(t))
        return point + t * inwardNormal;
  }
  return point;
}

BoneDepth BoneDepthProbe::measure(const Eigen::Vector3d& skinPoint) const
{
  BoneDepth out;
  if (!skinPoint.allFinite())
    return out;
  // From the skin itself: a map's skin point where its ray grazes the skin
  // (under the chin) can lie half a millimetre off it. Within a quarter of a
  // voxel the point is on the skin as far as the CT can tell, and stays.
  out.skinPoint = skinPoint;
  out.inwardNormal = skinNormal(skinPoint);
  if (out.inwardNormal.allFinite())
  {
    const Eigen::Vector3d onSkin = ontoSkin(skinPoint, out.inwardNormal);
    if ((onSkin - skinPoint).norm() > 0.25 * ct_.geometry().spacing.minCoeff())
    {
      const Eigen::Vector3d normal = skinNormal(onSkin);
      if (normal.allFinite())
        out.skinPoint = onSkin, out.inwardNormal = normal;
    }
    out.alongSkinNormal = alongRay(out.skinPoint, out.inwardNormal, &out.boneAlongNormal);
  }
  // The nearest bone is no farther than the bone along the normal; the
  // search reaches a voxel past it, for the surface's discretisation.
  const bool alongFound = std::isfinite(out.alongSkinNormal);
  const double radius = alongFound ? out.alongSkinNormal + ct_.geometry().spacing.norm() : searchDistance_;
  out.toNearestBone = toNearest(out.skinPoint, radius, &out.nearestBone);
  if (alongFound && !(out.toNearestBone <= out.alongSkinNormal))
  {
    out.toNearestBone = out.alongSkinNormal;
    out.nearestBone = out.boneAlongNormal;
  }
  return out;
}

DepthConvention LandmarkDepth::measuredBy() const
{
  if (convention == DepthConvention::SkinNormal && !std::isfinite(bone.alongSkinNormal) &&
      std::isfinite(bone.toNearestBone))
    return DepthConvention::NearestBone;
  return convention;
}

double LandmarkDepth::depth() const
{
  switch (measuredBy())
  {
  case DepthConvention::SkinNormal:
    return bone.alongSkinNormal;
  case DepthConvention::NearestBone:
    return bone.toNearestBone;
  case DepthConvention::NotADepth:
    break;
  }
  return RangeMap::quietNaN();
}

Eigen::Vector3d LandmarkDepth::boneEnd() const
{
  switch (measuredBy())
  {
  case DepthConvention::SkinNormal:
    return bone.boneAlongNormal;
  case DepthConvention::NearestBone:
    return bone.nearestBone;
  case DepthConvention::NotADepth:
    break;
  }
  return Eigen::Vector3d::Constant(RangeMap::quietNaN());
}

std::string LandmarkDepth::describeConvention() const
{
  std::string name = conventionName(measuredBy());
  if (measuredBy() != convention)
    name += " (no bone perpendicular to the skin)";
  return name;
}

} // namespace caps::seg
