#pragma once
/// @file SurfaceExtraction.h
/// @brief Closed triangle surfaces of label maps, in the patient frame.

#include <filesystem>

#include <vtkImageData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

namespace caps::seg {

/// How extractSurface() smooths and decimates.
struct SurfaceOptions
{
  /// Windowed-sinc smoothing iterations (Taubin's non-shrinking low-pass);
  /// 0 keeps the raw, staircased iso-surface.
  int smoothingIterations = 20;
  /// Pass band of the windowed-sinc filter (0..2, smaller smooths more);
  /// 0.1 removes the voxel staircase and keeps features a few voxels wide.
  double smoothingPassBand = 0.1;
  /// Fraction of triangles removed by quadric decimation for display (0..1);
  /// 0 keeps them all.
  double targetReduction = 0.0;
  /// Add point normals (consistently oriented outward).
  bool computeNormals = true;
};

/// The boundary of a 0/1 (or 0/label) mask as a closed triangle surface.
///
/// Flying edges (Schroeder et al. 2015) on the mask at 0.5, on the mask's
/// bounding box padded by one background voxel on every side so that the
/// surface closes where the mask meets the image border (a head cut by the
/// scan range stays a closed solid). The iso-surface of a binary mask lies
/// halfway between inside and outside voxel centres; the smoothing turns the
/// staircase into a surface whose enclosed volume stays close to the mask's
/// voxel volume. Points are in the patient frame (LPS, mm): origin +
/// direction * diag(spacing) * index, applied here because VTK 9.1's flying
/// edges ignores the image's direction matrix. Triangles are oriented with
/// outward normals whatever the handedness of the direction matrix.
///
/// @return an empty polydata when the mask has no voxel set.
/// @throws std::invalid_argument for a null image or one that is not one
///         scalar component.
vtkSmartPointer<vtkPolyData> extractSurface(vtkImageData* mask, const SurfaceOptions& options = {});

/// Writes @a surface as VTK XML PolyData (.vtp): appended raw data,
/// zlib-compressed, so every surface CAPS writes reads alike.
/// @throws std::runtime_error naming the file when it cannot be written.
void writeSurfaceVtp(vtkPolyData* surface, const std::filesystem::path& file);

} // namespace caps::seg
