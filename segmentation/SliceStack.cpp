#include "segmentation/SliceStack.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vtkMatrix3x3.h>

namespace caps::seg {
namespace {

Eigen::Vector3d vec(const SliceStackGeometry::Vector& v)
{
  return {v[0], v[1], v[2]};
}

// The slice normal: row x column.
Eigen::Vector3d normalOf(const SliceStackGeometry& g)
{
  return vec(g.row).cross(vec(g.column)).normalized();
}

std::string mm(double v)
{
  std::ostringstream out;
  out.precision(1);
  out << std::fixed << v;
  return out.str();
}

template <class T>
void resampleInto(const T* in, T* out, int nx, int ny, int nzIn, int nzOut, const SliceStackGeometry& g,
                  const std::vector<double>& along, double spacing, double padding)
{
  const Eigen::Vector3d normal = normalOf(g), row = vec(g.row).normalized(), column = vec(g.column).normalized();
  const Eigen::Vector3d origin = vec(g.positions.front());
  const double sx = g.pixelSpacing[0], sy = g.pixelSpacing[1];
  // Bilinear sample of input slice n at the point p (outside: padding).
  const auto sample = [&](int n, const Eigen::Vector3d& p) {
    const Eigen::Vector3d d = p - vec(g.positions[n]);
    const double u = d.dot(row) / sx, v = d.dot(column) / sy;
    if (u < -0.5 || v < -0.5 || u > nx - 0.5 || v > ny - 0.5)
      return padding;
    const double uc = std::clamp(u, 0.0, nx - 1.0), vc = std::clamp(v, 0.0, ny - 1.0);
    const int i0 = std::min(static_cast<int>(uc), nx - 2 < 0 ? 0 : nx - 2);
    const int j0 = std::min(static_cast<int>(vc), ny - 2 < 0 ? 0 : ny - 2);
    const int i1 = std::min(i0 + 1, nx - 1), j1 = std::min(j0 + 1, ny - 1);
    const double fu = uc - i0, fv = vc - j0;
    const T* slice = in + static_cast<size_t>(n) * nx * ny;
    const auto at = [&](int i, int j) { return static_cast<double>(slice[static_cast<size_t>(j) * nx + i]); };
    return (1 - fv) * ((1 - fu) * at(i0, j0) + fu * at(i1, j0)) + fv * ((1 - fu) * at(i0, j1) + fu * at(i1, j1));
  };
  for (int k = 0; k < nzOut; ++k)
  {
    const double s = along.front() + k * spacing;
    // The input slices around s.
    int b = static_cast<int>(std::lower_bound(along.begin(), along.end(), s - 1e-6) - along.begin());
    b = std::clamp(b, 0, nzIn - 1);
    const int a = std::max(0, along[b] > s + 1e-6 ? b - 1 : b);
    const double t = b == a ? 0.0 : (s - along[a]) / (along[b] - along[a]);
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
      {
        const Eigen::Vector3d p = origin + (i * sx) * row + (j * sy) * column + (s - along.front()) * normal;
        double value = sample(a, p);
        if (b != a && t > 0)
          value = (1 - t) * value + t * sample(b, p);
        if constexpr (std::is_integral_v<T>)
          value = std::round(value);
        out[(static_cast<size_t>(k) * ny + j) * nx + i] = static_cast<T>(value);
      }
  }
}

} // namespace

SliceStackReport analyseSliceStack(const SliceStackGeometry& g)
{
  SliceStackReport report;
  const size_t n = g.positions.size();
  if (n < 2)
    return report;
  const Eigen::Vector3d normal = normalOf(g);
  std::vector<double> along(n), gaps(n - 1);
  for (size_t k = 0; k < n; ++k)
    along[k] = vec(g.positions[k]).dot(normal);
  for (size_t k = 0; k + 1 < n; ++k)
    gaps[k] = along[k + 1] - along[k];
  std::vector<double> sorted = gaps;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  report.spacing = sorted[sorted.size() / 2];
  report.largestGap = *std::max_element(gaps.begin(), gaps.end());

  for (size_t k = 0; k + 1 < n; ++k)
  {
    if (gaps[k] < 1e-3)
    {
      report.refusal = "two slices lie at the same position (z = " + mm(along[k]) +
                       " mm): the folder mixes two acquisitions of the series";
      report.problems.push_back(report.refusal);
      return report;
    }
  }
  if (report.spacing <= 0)
  {
    report.refusal = "the slices are not ordered along their normal";
    return report;
  }
  for (size_t k = 0; k + 1 < n; ++k)
  {
    const double ratio = gaps[k] / report.spacing;
    if (std::abs(ratio - 1.0) <= 0.05)
      continue;
    report.uneven = true;
    const int missing = static_cast<int>(std::lround(ratio)) - 1;
    std::ostringstream text;
    if (missing >= 1 && std::abs(ratio - std::round(ratio)) < 0.1)
    {
      report.missingSlices += missing;
      text << missing << " slice" << (missing > 1 ? "s" : "") << " missing between z = " << mm(along[k])
           << " and z = " << mm(along[k + 1]) << " mm";
    }
    else
      text << "uneven slice spacing: " << mm(gaps[k]) << " mm instead of " << mm(report.spacing)
           << " mm between z = " << mm(along[k]) << " and z = " << mm(along[k + 1]) << " mm";
    report.problems.push_back(text.str());
    if (ratio > kLargestInterpolatedGap)
    {
      report.refusal = "a gap of " + mm(gaps[k]) + " mm between z = " + mm(along[k]) + " and z = " + mm(along[k + 1]) +
                       " mm is too large to interpolate: the series is incomplete";
      return report;
    }
  }
  // Gantry tilt: the slices march along a direction that is not their normal.
  const Eigen::Vector3d stacking = vec(g.positions.back()) - vec(g.positions.front());
  const double cosine = std::clamp(std::abs(stacking.normalized().dot(normal)), 0.0, 1.0);
  report.tiltDegrees = std::acos(cosine) * 180.0 / M_PI;
  if (report.tiltDegrees > 0.1)
    report.problems.push_back("the slices are sheared by a gantry tilt of " + mm(report.tiltDegrees) + " degrees");
  report.needsResampling = report.uneven || report.tiltDegrees > 0.1;
  return report;
}

vtkSmartPointer<vtkImageData> resampleSliceStack(vtkImageData* stack, const SliceStackGeometry& g,
                                                 const SliceStackReport& report, double padding)
{
  const int* dims = stack->GetDimensions();
  const int nx = dims[0], ny = dims[1], nzIn = dims[2];
  const Eigen::Vector3d normal = normalOf(g), row = vec(g.row).normalized(), column = vec(g.column).normalized();
  std::vector<double> along(g.positions.size());
  for (size_t k = 0; k < along.size(); ++k)
    along[k] = vec(g.positions[k]).dot(normal);
  const int nzOut = static_cast<int>(std::lround((along.back() - along.front()) / report.spacing)) + 1;

  auto out = vtkSmartPointer<vtkImageData>::New();
  out->SetDimensions(nx, ny, nzOut);
  out->SetSpacing(g.pixelSpacing[0], g.pixelSpacing[1], report.spacing);
  const auto& o = g.positions.front();
  out->SetOrigin(o[0], o[1], o[2]);
  out->SetDirectionMatrix(row.x(), column.x(), normal.x(), row.y(), column.y(), normal.y(), row.z(), column.z(),
                          normal.z());
  out->AllocateScalars(stack->GetScalarType(), 1);
  if (stack->GetScalarType() == VTK_SHORT)
    resampleInto(static_cast<const short*>(stack->GetScalarPointer()), static_cast<short*>(out->GetScalarPointer()), nx,
                 ny, nzIn, nzOut, g, along, report.spacing, padding);
  else
    resampleInto(static_cast<const float*>(stack->GetScalarPointer()), static_cast<float*>(out->GetScalarPointer()), nx,
                 ny, nzIn, nzOut, g, along, report.spacing, padding);
  return out;
}

} // namespace caps::seg
