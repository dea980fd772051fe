#pragma once
// A synthetic head CT with known answers, built in the tests.
//
//        air (-1000 HU)
//     .-----------------.        head: ellipsoid of soft tissue (40 HU),
//    /   skull (700 HU)  \             semi-axes a (x), b (y), c (z) in mm
//   |   .-----------.     |      skull: ellipsoidal shell, 6 mm thick
//   |  |  o cavity   |    |      cavity: air sphere in the "brain" (filled)
//   |  |       . isl |    |      island: small bone sphere (removed)
//    \  '-----------'    /
//     '--------+--------'        post: thin cylinder (3 mm) joining the head
//  ============|============     table: slab behind the head (+y, posterior,
//                                       patient supine), 200 HU (removed)
//
// Values are partial-volume blurred (Gaussian edge of sigma mm) and carry
// Gaussian noise; everything is evaluated at each voxel's LPS position, so a
// rotated direction matrix samples the same anatomy in a rotated grid.

#include <array>
#include <cmath>
#include <cstdint>
#include <random>

#include <vtkImageData.h>
#include <vtkMatrix3x3.h>
#include <vtkSmartPointer.h>

namespace caps::test {

/// Rotation by angle (degrees) about an axis (normalised here), Rodrigues' formula.
inline vtkSmartPointer<vtkMatrix3x3> rotation(double degrees, std::array<double, 3> axis)
{
  const double norm = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
  for (double& a : axis)
    a /= norm;
  const double t = degrees * M_PI / 180.0, c = std::cos(t), s = std::sin(t);
  const double k[3][3] = {{0, -axis[2], axis[1]}, {axis[2], 0, -axis[0]}, {-axis[1], axis[0], 0}};
  auto m = vtkSmartPointer<vtkMatrix3x3>::New();
  for (int r = 0; r < 3; ++r)
    for (int q = 0; q < 3; ++q)
    {
      double k2 = 0;
      for (int l = 0; l < 3; ++l)
        k2 += k[r][l] * k[l][q];
      m->SetElement(r, q, (r == q ? 1.0 : 0.0) + s * k[r][q] + (1 - c) * k2);
    }
  return m;
}

struct Phantom
{
  std::array<double, 3> centre{0.0, 0.0, 0.0};
  std::array<double, 3> head{50.0, 60.0, 55.0}; ///< semi-axes, mm
  double skullOffset = 6.0;                     ///< skin to outer skull surface, mm
  double skullThickness = 6.0;
  std::array<double, 3> cavityCentre{0.0, -10.0, 5.0}; ///< relative to centre
  double cavityRadius = 10.0;
  std::array<double, 3> islandCentre{15.0, 15.0, -10.0}; ///< relative to centre
  double islandRadius = 3.0;                             ///< 113 mm³ < 500 mm³
  bool table = true;
  double tableGap = 4.0; ///< head surface to table top along +y, mm
  double tableThickness = 10.0;
  double postRadius = 1.5; ///< the thin contact between head and table
  double tissueHu = 40, boneHu = 700, airHu = -1000, tableHu = 200;
  double blurSigma = 0.6; ///< mm
  double noiseHu = 20;

  static double normalCdf(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }

  /// Fraction of a blurred edge inside an ellipsoid of semi-axes s centred at
  /// c, from a first-order signed distance to its surface.
  double insideEllipsoid(const double p[3], const std::array<double, 3>& c, const std::array<double, 3>& s) const
  {
    double q = 0, g[3];
    for (int a = 0; a < 3; ++a)
    {
      const double u = p[a] - c[a];
      q += u * u / (s[a] * s[a]);
      g[a] = u / (s[a] * s[a]);
    }
    const double root = std::sqrt(q);
    if (root < 1e-9)
      return 1.0;
    const double gradNorm = std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]) / root;
    const double distance = (root - 1.0) / gradNorm;
    return normalCdf(-distance / blurSigma);
  }

  std::array<double, 3> offsetAxes(double offset) const
  {
    return {head[0] - offset, head[1] - offset, head[2] - offset};
  }

  std::array<double, 3> at(const std::array<double, 3>& relative) const
  {
    return {centre[0] + relative[0], centre[1] + relative[1], centre[2] + relative[2]};
  }

  /// HU at a point, without noise.
  double hu(const double p[3]) const
  {
    const double fHead = insideEllipsoid(p, centre, head);
    const double fOuter = insideEllipsoid(p, centre, offsetAxes(skullOffset));
    const double fInner = insideEllipsoid(p, centre, offsetAxes(skullOffset + skullThickness));
    const double r = cavityRadius, ri = islandRadius;
    const double fCavity = insideEllipsoid(p, at(cavityCentre), {r, r, r});
    const double fIsland = insideEllipsoid(p, at(islandCentre), {ri, ri, ri});
    double v = airHu + (tissueHu - airHu) * fHead;
    v += (boneHu - tissueHu) * (fOuter - fInner);
    v += (airHu - tissueHu) * fCavity + (boneHu - tissueHu) * fIsland;
    if (table)
    {
      // Slab: y in [top, top + thickness], all x and z. Post: cylinder along
      // y at the head's back-most point, from inside the head into the slab.
      const double top = centre[1] + head[1] + tableGap;
      const double fSlab = normalCdf((p[1] - top) / blurSigma) * normalCdf((top + tableThickness - p[1]) / blurSigma);
      const double dx = p[0] - centre[0], dz = p[2] - centre[2];
      const double fPost = normalCdf((postRadius - std::sqrt(dx * dx + dz * dz)) / blurSigma) *
                           normalCdf((p[1] - (centre[1] + head[1] - 3.0)) / blurSigma) *
                           normalCdf((top + 1.0 - p[1]) / blurSigma);
      const double fTable = std::min(1.0, fSlab + fPost) * (1.0 - fHead);
      v += (tableHu - airHu) * fTable;
    }
    return v;
  }

  /// Volume of an ellipsoid with the head's semi-axes moved outward by delta.
  double ellipsoidVolume(const std::array<double, 3>& s, double delta = 0) const
  {
    return 4.0 / 3.0 * M_PI * (s[0] + delta) * (s[1] + delta) * (s[2] + delta);
  }

  /// Where a threshold crosses a blurred edge from `low` to `high`, as a
  /// distance outward from the true edge into the `low` side (negative:
  /// inside the `high` side).
  double thresholdShift(double threshold, double low, double high) const
  {
    // fraction f inside = Phi(-d/sigma) = (threshold - low)/(high - low).
    const double f = (threshold - low) / (high - low);
    // Solve Phi(x) = f by bisection (x = -d/sigma).
    double lo = -10, hi = 10;
    for (int i = 0; i < 100; ++i)
    {
      const double mid = 0.5 * (lo + hi);
      (normalCdf(mid) < f ? lo : hi) = mid;
    }
    return -0.5 * (lo + hi) * blurSigma;
  }

  /// The phantom CT (int16 HU) on a grid of dims voxels with the given
  /// spacing and direction, centred on the head.
  vtkSmartPointer<vtkImageData> image(const std::array<int, 3>& dims, const std::array<double, 3>& spacing,
                                      vtkMatrix3x3* direction = nullptr,
                                      const std::array<double, 3>& gridCentre = {0, 0, 0}, unsigned seed = 7) const
  {
    auto identity = vtkSmartPointer<vtkMatrix3x3>::New();
    if (!direction)
      direction = identity;
    double d[3][3];
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        d[r][c] = direction->GetElement(r, c) * spacing[c];
    double origin[3];
    for (int r = 0; r < 3; ++r)
    {
      origin[r] = gridCentre[r];
      for (int c = 0; c < 3; ++c)
        origin[r] -= d[r][c] * 0.5 * (dims[c] - 1);
    }
    auto image = vtkSmartPointer<vtkImageData>::New();
    image->SetDimensions(dims[0], dims[1], dims[2]);
    image->SetSpacing(spacing[0], spacing[1], spacing[2]);
    image->SetOrigin(origin);
    image->SetDirectionMatrix(direction);
    image->AllocateScalars(VTK_SHORT, 1);
    auto* out = static_cast<std::int16_t*>(image->GetScalarPointer());
    std::mt19937 random(seed);
    std::normal_distribution<double> noise(0.0, noiseHu);
    std::size_t n = 0;
    for (int k = 0; k < dims[2]; ++k)
      for (int j = 0; j < dims[1]; ++j)
        for (int i = 0; i < dims[0]; ++i, ++n)
        {
          double p[3];
          for (int r = 0; r < 3; ++r)
            p[r] = origin[r] + d[r][0] * i + d[r][1] * j + d[r][2] * k;
          out[n] = static_cast<std::int16_t>(std::lround(hu(p) + noise(random)));
        }
    return image;
  }
};

} // namespace caps::test
