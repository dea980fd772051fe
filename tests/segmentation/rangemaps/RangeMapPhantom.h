#pragma once
// Synthetic head phantoms for the range map tests: analytic shapes sampled
// with partial volume, blurred by a Gaussian point spread, plus noise.

#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vtkImageData.h>
#include <vtkSmartPointer.h>

#include "segmentation/RangeMapImageGeometry.h"

namespace caps::seg::test {

/// A solid with an implicit function (< 1 inside) and its outermost hit along a ray.
struct Shape
{
  virtual ~Shape() = default;
  virtual double implicit(const Eigen::Vector3d& p) const = 0;
  bool inside(const Eigen::Vector3d& p) const { return implicit(p) < 1.0; }
  /// Largest r >= 0 with base + r·dir on the surface, NaN if none (dir unit).
  virtual double outermostHit(const Eigen::Vector3d& base, const Eigen::Vector3d& dir) const = 0;
};

/// Largest root of a r² + b r + c = 0, NaN if none.
inline double largestRoot(double a, double b, double c)
{
  const double disc = b * b - 4 * a * c;
  if (disc < 0.0 || a == 0.0)
    return std::numeric_limits<double>::quiet_NaN();
  return (-b + std::sqrt(disc)) / (2 * a);
}

struct Ellipsoid : Shape
{
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Vector3d semiAxes = Eigen::Vector3d::Ones();
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity(); ///< columns: world directions of the semi-axes

  Ellipsoid(const Eigen::Vector3d& c, const Eigen::Vector3d& a) : centre(c), semiAxes(a) {}
  double implicit(const Eigen::Vector3d& p) const override
  {
    return (rotation.transpose() * (p - centre)).cwiseQuotient(semiAxes).squaredNorm();
  }
  double outermostHit(const Eigen::Vector3d& base, const Eigen::Vector3d& dir) const override
  {
    const Eigen::Vector3d q0 = (rotation.transpose() * (base - centre)).cwiseQuotient(semiAxes);
    const Eigen::Vector3d qd = (rotation.transpose() * dir).cwiseQuotient(semiAxes);
    const double r = largestRoot(qd.squaredNorm(), 2 * q0.dot(qd), q0.squaredNorm() - 1.0);
    return r >= 0.0 ? r : std::numeric_limits<double>::quiet_NaN();
  }
};

/// An infinite circular cylinder.
struct Cylinder : Shape
{
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  double radius = 1.0;

  Cylinder(const Eigen::Vector3d& p, const Eigen::Vector3d& a, double r) : point(p), axis(a.normalized()), radius(r) {}
  double implicit(const Eigen::Vector3d& p) const override
  {
    const Eigen::Vector3d w = p - point;
    return (w - w.dot(axis) * axis).squaredNorm() / (radius * radius);
  }
  double outermostHit(const Eigen::Vector3d& base, const Eigen::Vector3d& dir) const override
  {
    Eigen::Vector3d w = base - point;
    w -= w.dot(axis) * axis;
    const Eigen::Vector3d d = dir - dir.dot(axis) * axis;
    const double r = largestRoot(d.squaredNorm(), 2 * w.dot(d), w.squaredNorm() - radius * radius);
    return r >= 0.0 ? r : std::numeric_limits<double>::quiet_NaN();
  }
};

/// An axis-aligned box (the CT table).
struct Box : Shape
{
  Eigen::Vector3d lo, hi;
  Box(const Eigen::Vector3d& l, const Eigen::Vector3d& h) : lo(l), hi(h) {}
  double implicit(const Eigen::Vector3d& p) const override
  {
    return ((p.array() > lo.array()).all() && (p.array() < hi.array()).all()) ? 0.0 : 2.0;
  }
  double outermostHit(const Eigen::Vector3d&, const Eigen::Vector3d&) const override
  {
    return std::numeric_limits<double>::quiet_NaN();
  }
};

/// Empty float image with the given grid.
inline vtkSmartPointer<vtkImageData> makeImage(const ImageGeometry& g, int vtkType)
{
  auto image = vtkSmartPointer<vtkImageData>::New();
  g.applyTo(image);
  image->AllocateScalars(vtkType, 1);
  return image;
}

/// A grid of dims voxels of the given spacing and direction, centred on centre (world).
inline ImageGeometry centredGeometry(const Eigen::Vector3i& dims, const Eigen::Vector3d& spacing,
                                     const Eigen::Matrix3d& direction, const Eigen::Vector3d& centre)
{
  ImageGeometry g;
  g.extent = {0, dims.x() - 1, 0, dims.y() - 1, 0, dims.z() - 1};
  g.spacing = spacing;
  g.direction = direction;
  g.origin = Eigen::Vector3d::Zero();
  g.origin = centre - g.indexToWorldMatrix() * (dims.cast<double>() - Eigen::Vector3d::Ones()) / 2.0;
  return g;
}

/// Fraction of each voxel inside the shape: corners of the voxel decide, boundary voxels are
/// supersampled n³.
inline std::vector<float> partialVolume(const ImageGeometry& g, const Shape& shape, int n = 4)
{
  const auto dims = g.dimensions();
  const int cx = dims[0] + 1, cy = dims[1] + 1, cz = dims[2] + 1;
  std::vector<unsigned char> corner(static_cast<std::size_t>(cx) * cy * cz);
  for (int k = 0; k < cz; ++k)
    for (int j = 0; j < cy; ++j)
      for (int i = 0; i < cx; ++i)
        corner[i + cx * (j + static_cast<std::size_t>(cy) * k)] =
          shape.inside(g.indexToWorld(Eigen::Vector3d(i - 0.5, j - 0.5, k - 0.5)));
  std::vector<float> f(static_cast<std::size_t>(dims[0]) * dims[1] * dims[2]);
  std::size_t o = 0;
  for (int k = 0; k < dims[2]; ++k)
    for (int j = 0; j < dims[1]; ++j)
      for (int i = 0; i < dims[0]; ++i, ++o)
      {
        int sum = 0;
        for (int c = 0; c < 8; ++c)
          sum += corner[(i + (c & 1)) + cx * ((j + ((c >> 1) & 1)) + static_cast<std::size_t>(cy) * (k + (c >> 2)))];
        if (sum == 0 || sum == 8)
        {
          f[o] = sum ? 1.0f : 0.0f;
          continue;
        }
        int in = 0;
        for (int c = 0; c < n; ++c)
          for (int b = 0; b < n; ++b)
            for (int a = 0; a < n; ++a)
              in += shape.inside(g.indexToWorld(
                Eigen::Vector3d(i - 0.5 + (a + 0.5) / n, j - 0.5 + (b + 0.5) / n, k - 0.5 + (c + 0.5) / n)));
        f[o] = static_cast<float>(in) / (n * n * n);
      }
  return f;
}

/// Separable Gaussian blur, sigma in mm along each index axis (edges clamped).
inline void gaussianBlur(std::vector<float>& v, const ImageGeometry& g, double sigmaMm)
{
  const auto dims = g.dimensions();
  const std::ptrdiff_t stride[3] = {1, dims[0], static_cast<std::ptrdiff_t>(dims[0]) * dims[1]};
  std::vector<float> tmp(v.size());
  for (int a = 0; a < 3; ++a)
  {
    const double s = sigmaMm / g.spacing[a];
    const int radius = static_cast<int>(std::ceil(3.5 * s));
    std::vector<double> kernel(2 * radius + 1);
    double sum = 0;
    for (int t = -radius; t <= radius; ++t)
      sum += kernel[t + radius] = std::exp(-0.5 * t * t / (s * s));
    for (double& w : kernel)
      w /= sum;
    std::size_t o = 0;
    for (int k = 0; k < dims[2]; ++k)
      for (int j = 0; j < dims[1]; ++j)
        for (int i = 0; i < dims[0]; ++i, ++o)
        {
          const int idx[3] = {i, j, k};
          double acc = 0;
          for (int t = -radius; t <= radius; ++t)
          {
            const int p = std::clamp(idx[a] + t, 0, dims[a] - 1);
            acc += kernel[t + radius] * v[o + (p - idx[a]) * stride[a]];
          }
          tmp[o] = static_cast<float>(acc);
        }
    v.swap(tmp);
  }
}

/// Tissue values of the phantoms (HU).
constexpr double airHu = -1000.0;
constexpr double softHu = 40.0;
constexpr double boneHu = 1000.0;
/// Thresholds at the middle of each step: the iso-surface of a blurred step
/// then lies on the true edge (a threshold off the middle shifts it by
/// σ·Φ⁻¹(level), which is physics, not the method's error).
constexpr double skinMidHu = 0.5 * (airHu + softHu);
constexpr double boneMidHu = 0.5 * (softHu + boneHu);

struct Phantom
{
  vtkSmartPointer<vtkImageData> ct;
  vtkSmartPointer<vtkImageData> body;
  vtkSmartPointer<vtkImageData> bone;
};

/// CT of skin ⊃ bone (plus optional extra solids of soft-tissue density, e.g. a
/// table, kept out of the body mask), blurred with sigmaMm and noise of noiseHu.
/// Masks: threshold at the mid-levels; the body also near the skin solid only,
/// so the extras stay out (unless extrasInBody).
inline Phantom makePhantom(const ImageGeometry& g, const Shape& skin, const Shape& bone,
                           const std::vector<const Shape*>& extras, double sigmaMm, double noiseHu, int vtkType,
                           unsigned seed = 7, bool extrasInBody = false)
{
  std::vector<float> fs = partialVolume(g, skin);
  const std::vector<float> fb = partialVolume(g, bone);
  std::vector<float> hu(fs.size());
  std::vector<float> fe(fs.size(), 0.0f);
  for (const Shape* e : extras)
  {
    const std::vector<float> f = partialVolume(g, *e);
    for (std::size_t o = 0; o < fe.size(); ++o)
      fe[o] = std::max(fe[o], f[o]);
  }
  for (std::size_t o = 0; o < hu.size(); ++o)
    hu[o] = static_cast<float>(airHu + (softHu - airHu) * std::max(fs[o], fe[o]) + (boneHu - softHu) * fb[o]);
  gaussianBlur(hu, g, sigmaMm);
  std::mt19937 random(seed);
  std::normal_distribution<float> noise(0.0f, static_cast<float>(noiseHu));
  for (float& v : hu)
    v += noiseHu > 0 ? noise(random) : 0.0f;

  const auto dims = g.dimensions();
  auto index = [&](std::size_t o) {
    return Eigen::Vector3d(static_cast<double>(o % dims[0]), static_cast<double>((o / dims[0]) % dims[1]),
                           static_cast<double>(o / (static_cast<std::size_t>(dims[0]) * dims[1])));
  };
  Phantom p;
  p.ct = makeImage(g, vtkType);
  p.body = makeImage(g, VTK_UNSIGNED_CHAR);
  p.bone = makeImage(g, VTK_UNSIGNED_CHAR);
  auto* body = static_cast<unsigned char*>(p.body->GetScalarPointer());
  auto* boneMask = static_cast<unsigned char*>(p.bone->GetScalarPointer());
  for (std::size_t o = 0; o < hu.size(); ++o)
  {
    if (vtkType == VTK_SHORT)
      static_cast<short*>(p.ct->GetScalarPointer())[o] = static_cast<short>(std::lround(hu[o]));
    else
      static_cast<float*>(p.ct->GetScalarPointer())[o] = hu[o];
    // The body mask is the threshold near the skin solid (the segmenter's
    // job, done here by knowing the answer): the extras stay out.
    const bool nearSkin = skin.implicit(g.indexToWorld(index(o))) < 1.2;
    body[o] = hu[o] >= skinMidHu && (extrasInBody || nearSkin);
    boneMask[o] = body[o] && hu[o] >= boneMidHu;
  }
  return p;
}

} // namespace caps::seg::test
