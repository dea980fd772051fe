#include "segmentation/RangeMapImageGeometry.h"

#include <cmath>
#include <stdexcept>

#include <Eigen/LU>
#include <vtkImageData.h>
#include <vtkMatrix3x3.h>

namespace caps::seg {

ImageGeometry ImageGeometry::of(vtkImageData* image)
{
  if (!image)
    throw std::invalid_argument("No image was given.");
  ImageGeometry g;
  image->GetExtent(g.extent.data());
  for (int a = 0; a < 3; ++a)
  {
    g.origin[a] = image->GetOrigin()[a];
    g.spacing[a] = image->GetSpacing()[a];
  }
  if (vtkMatrix3x3* d = image->GetDirectionMatrix())
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        g.direction(r, c) = d->GetElement(r, c);
  return g;
}

std::array<int, 3> ImageGeometry::dimensions() const
{
  return {extent[1] - extent[0] + 1, extent[3] - extent[2] + 1, extent[5] - extent[4] + 1};
}

Eigen::Matrix3d ImageGeometry::indexToWorldMatrix() const
{
  return direction * spacing.asDiagonal();
}

Eigen::Vector3d ImageGeometry::indexToWorld(const Eigen::Vector3d& index) const
{
  return origin + indexToWorldMatrix() * index;
}

Eigen::Vector3d ImageGeometry::worldToIndex(const Eigen::Vector3d& world) const
{
  return indexToWorldMatrix().inverse() * (world - origin);
}

bool ImageGeometry::sameGrid(const ImageGeometry& other, double tolerance) const
{
  if (extent != other.extent)
    return false;
  // Compare the corners of the grid: affine maps agree everywhere if they agree there.
  for (int c = 0; c < 8; ++c)
  {
    const Eigen::Vector3d index(c & 1 ? extent[1] : extent[0], c & 2 ? extent[3] : extent[2],
                                c & 4 ? extent[5] : extent[4]);
    if ((indexToWorld(index) - other.indexToWorld(index)).norm() > tolerance)
      return false;
  }
  return true;
}

void ImageGeometry::applyTo(vtkImageData* image) const
{
  image->SetExtent(const_cast<int*>(extent.data()));
  image->SetOrigin(origin.data());
  image->SetSpacing(spacing.data());
  image->SetDirectionMatrix(direction(0, 0), direction(0, 1), direction(0, 2), direction(1, 0), direction(1, 1),
                            direction(1, 2), direction(2, 0), direction(2, 1), direction(2, 2));
}

} // namespace caps::seg
