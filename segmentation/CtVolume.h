#pragma once
/// @file CtVolume.h
/// @brief A CT volume as read from disk: HU voxels in the DICOM patient frame.

#include <map>
#include <string>
#include <vector>

#include <vtkImageData.h>
#include <vtkSmartPointer.h>

namespace caps::seg {

/// A CT volume in Hounsfield units.
///
/// The image carries origin, spacing and the 3x3 direction matrix, all in the
/// DICOM patient frame (LPS, mm), so voxel (i,j,k) sits at
/// origin + direction * diag(spacing) * (i,j,k). Scalars are int16 when the
/// rescale maps stored values to whole HU, float otherwise.
struct CtVolume
{
  vtkSmartPointer<vtkImageData> image;
  /// DICOM patient/study/series fields by keyword ("PatientName", "StudyDate",
  /// "SeriesDescription", ...); empty for formats that carry none.
  std::map<std::string, std::string> metadata;
  /// The file or folder it came from.
  std::string sourcePath;
  /// Things the user should know about the data that did not stop the read.
  std::vector<std::string> warnings;
};

} // namespace caps::seg
