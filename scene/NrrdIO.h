#pragma once

#include <vtkImageData.h>
#include <vtkSmartPointer.h>

#include <Eigen/Core>
#include <filesystem>

namespace caps {

/// @brief Small NRRD (NRRD0004) reader and writer, enough for the scene bundle.
///
/// 3D images are written with `space: left-posterior-superior`, `space
/// directions` (direction matrix columns times spacing) and `space origin`, so
/// 3D Slicer and ParaView place them where CAPS does. Data are little endian,
/// gzip (fast level) by default. Reading accepts raw and gzip encodings,
/// either endianness, LPS/RAS/LAS spaces, attached data only.
/// @warning Single-component scalars only; throws SceneError naming the file
/// on anything else, and on truncated or foreign files.
class NrrdIO
{
public:
  enum class Encoding
  {
    Gzip,
    Raw
  };

  /// Writes a single-component image (any integer or float VTK scalar type)
  /// with its origin, spacing and direction matrix (patient LPS, mm).
  static void writeImage(vtkImageData* image, const std::filesystem::path& file, Encoding encoding = Encoding::Gzip);
  /// Reads a 2D or 3D single-component image; the extent starts at 0.
  static vtkSmartPointer<vtkImageData> readImage(const std::filesystem::path& file);

  /// Writes a 2D float image, rows fastest (Eigen's column-major order). NaN is kept.
  static void writeMatrix(const Eigen::MatrixXf& values, const std::filesystem::path& file,
                          Encoding encoding = Encoding::Gzip);
  /// Reads a 2D float image written by writeMatrix (sizes: rows cols).
  static Eigen::MatrixXf readMatrix(const std::filesystem::path& file);
};

} // namespace caps
