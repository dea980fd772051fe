#pragma once
/// @file RangeMapPreview.h
/// @brief PNG pictures of range and thickness maps with a colour bar in mm,
/// drawn without OpenGL or a display (for the command line and CI).

#include <filesystem>
#include <string>

#include <Eigen/Core>
#include <vtkImageData.h>
#include <vtkSmartPointer.h>

namespace caps {

/// What a preview shows and how.
struct PreviewStyle
{
  std::string title;       ///< above the map: "Soft-tissue thickness, radial"
  std::string unit = "mm"; ///< above the colour bar
  double low = 0.0;        ///< value at the bottom of the colour bar
  double high = 30.0;      ///< value at the top; values beyond are clamped
  int pixelsPerSample = 2; ///< the map's samples as squares of this many pixels
  /// Size of the text, margins and ticks against the defaults (13-18 px
  /// text): a map drawn large for print scales them with it.
  double textScale = 1.0;
};

/// The style for a map of distances from the axis (skin, scan): its 2nd..98th
/// percentile widened to whole 10 mm, so outliers do not wash out the face.
PreviewStyle rangeStyle(const Eigen::MatrixXf& values, std::string title);

/// @brief Draws a range map as an RGB picture (y up, as vtkImageData and vtkPNGWriter).
///
/// θ runs horizontally with the face (θ = -π/2) in the middle of the picture
/// and the back of the head at both edges, patient right on the left, as
/// when facing the patient; z runs up. Values map to viridis (perceptually
/// uniform, readable in grey and by colour-blind readers) between low and
/// high; NaN samples (no surface) are grey. A colour bar with tick labels
/// in the style's unit is on the right, the title on top, z (mm along the
/// axis) ticks on the left and the directions (back, right, face, left)
/// below. Text is rendered with VTK's FreeType tools into the image: no
/// OpenGL context, no X server.
/// @param values rows θ (θ_i = -π + 2π i / rows), columns z from zMin to zMax.
vtkSmartPointer<vtkImageData> renderRangeMapPreview(const Eigen::MatrixXf& values, double zMin, double zMax,
                                                    const PreviewStyle& style);

/// renderRangeMapPreview() written as PNG.
/// @throws std::runtime_error naming the file when it cannot be written.
void writeRangeMapPreview(const Eigen::MatrixXf& values, double zMin, double zMax, const PreviewStyle& style,
                          const std::filesystem::path& file);

/// Viridis at t in [0, 1] (clamped), as 8-bit RGB.
void viridis(double t, unsigned char rgb[3]);

} // namespace caps
