#pragma once
/// @file Figure.h
/// @brief Declarative offscreen figures (the plan report, the results and
/// expression exports): surfaces, incision lines, colour bars; their cameras
/// and the pixels they render to.

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <vtkSmartPointer.h>

#include "render/Camera.h"
#include "render/ColourMaps.h"

class vtkImageData;
class vtkPolyData;
class QImage;

namespace caps::seg {
class CylindricalFrame;
}

namespace caps::render {

/// An RGB colour, each channel in [0, 1].
using Rgb = std::array<double, 3>;

/// @brief One surface of a figure and how it is coloured.
///
/// Point normals are computed (smooth shading) when the surface has none.
struct SurfaceLayer
{
  enum class Colouring
  {
    Solid,       ///< colour
    PointRgb,    ///< the unsigned char 3- (or 4-) component point array `array`, used as is
    PointScalars ///< the scalar point array `array` through colourMap over range (magnitude if it has several components)
  };

  vtkSmartPointer<vtkPolyData> surface;
  Colouring colouring = Colouring::Solid;
  Rgb colour{0.90, 0.76, 0.66};
  std::string array;
  /// Scalar range mapped to the colour map's ends; values outside take the end colours, NaN is grey.
  std::array<double, 2> range{0.0, 1.0};
  ColourMap colourMap = ColourMap::Viridis;
  double opacity = 1.0;
  /// Shaded by the lights (default); false shows the colours exactly (ambient only).
  bool lit = true;

  static SurfaceLayer solid(vtkSmartPointer<vtkPolyData> surface, const Rgb& colour, double opacity = 1.0);
  /// Per-point colours, e.g. the display surfaces' "skin_colour".
  static SurfaceLayer pointColours(vtkSmartPointer<vtkPolyData> surface, std::string array = "skin_colour");
  static SurfaceLayer scalars(vtkSmartPointer<vtkPolyData> surface, std::string array, double min, double max,
                              ColourMap map);
};

/// @brief A 3D polyline drawn over the surfaces (§3.3.1: solid lines for incisions, numbered points).
///
/// Its points are moved towards the camera by `lift` mm at render time,
/// which does not change where they project but keeps the line in front of
/// the skin it lies on; a surface in front of it still hides it. Labels are
/// drawn in 2D beside their points, away from the line, in textPoints bold;
/// the label of a point hidden by a surface (or outside the frame) is left out.
struct LineLayer
{
  std::vector<Eigen::Vector3d> points;
  bool closed = false;
  Rgb colour{0.42, 0.0, 0.55}; ///< surgical marker violet
  double widthPixels = 8.0;
  /// Labels at the points: empty, or one per point ("" for none).
  std::vector<std::string> labels;
  /// A dot at every labelled point.
  bool markLabelledPoints = true;
  /// mm towards the camera; negative: 0.6 % of the camera distance.
  double lift = -1.0;

  /// Labels "1", "2", … at every point (or at the given point indices, numbered in that order).
  void numberPoints();
  void numberPoints(const std::vector<std::size_t>& indices);
};

/// @brief A colour bar on the right of the figure: the map, its range, a title with units.
///
/// Drawn as a framed vertical strip with ticks and labels at their values and
/// the title written upwards beside it, all in textPoints at print size.
struct ColourBar
{
  std::string title; ///< with units, e.g. "von Mises stress (kPa)"
  std::array<double, 2> range{0.0, 1.0};
  ColourMap colourMap = ColourMap::Viridis;
  int labelCount = 5;               ///< evenly spaced from range[0] to range[1], each level with its value
  std::string labelFormat = "%.3g"; ///< printf format of one double
};

/// @brief Everything a figure shows. Render with renderFigure().
///
/// Text (labels, colour bar) is sized in points for the printed width, so a
/// figure printed printWidthMm wide shows textPoints-point text whatever its
/// pixel size. With a colour bar the scene occupies the left part of the
/// image (sceneViewport()): fit cameras to sceneAspect().
struct Figure
{
  int width = 1600;
  int height = 1200;
  Camera camera;
  std::vector<SurfaceLayer> surfaces;
  std::vector<LineLayer> lines;
  std::optional<ColourBar> colourBar;
  Rgb background{1.0, 1.0, 1.0};
  double printWidthMm = 80.0;
  double textPoints = 8.0;
  /// MSAA samples (0: none); FXAA is used in addition when fxaa is set.
  int multiSamples = 8;
  bool fxaa = false;

  /// Pixels per printed point (1/72 inch) at printWidthMm.
  double pixelsPerPoint() const;
  /// The scene's viewport in normalised window coordinates {x0, y0, x1, y1} (VTK: y up).
  std::array<double, 4> sceneViewport() const;
  /// Width / height of the scene's viewport in pixels.
  double sceneAspect() const;
};

/// @name Cameras
/// Cameras look at a target from a direction and frame a sphere, a box or a
/// point set. The same Camera renders pre and post so they are comparable.
///@{
/// The θ of a view in the head's cylindrical frame (θ = -π/2 is the face).
enum class View
{
  Front,        ///< θ = -π/2
  ObliqueLeft,  ///< 45° towards the patient's left: θ = -π/4
  ObliqueRight, ///< θ = -3π/4
  ProfileLeft,  ///< the patient's left side: θ = 0
  ProfileRight, ///< θ = -π
};
double viewTheta(View view);

/// A camera at target + distance·toCamera, view-up made orthogonal to the view direction,
/// the distance such that a sphere of `radius` around target fits the frame (aspect = width/height)
/// with `margin` (1.1: 10 % around).
/// @throws std::invalid_argument for a zero direction, an up parallel to it, radius <= 0 or aspect <= 0.
Camera lookAtCamera(const Eigen::Vector3d& target, const Eigen::Vector3d& toCamera, const Eigen::Vector3d& viewUp,
                    double radius, double aspect, double viewAngleDeg = 20.0, double margin = 1.1);

/// As lookAtCamera, but the distance is the smallest at which every point projects inside the
/// frame shrunk by `margin`, and the target is moved so they are centred. Exact for perspective.
Camera fitCamera(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& toCamera,
                 const Eigen::Vector3d& viewUp, double aspect, double viewAngleDeg = 20.0, double margin = 1.1);
/// fitCamera on the eight corners of bounds {xmin, xmax, ymin, ymax, zmin, zmax}.
Camera fitCamera(const std::array<double, 6>& bounds, const Eigen::Vector3d& toCamera, const Eigen::Vector3d& viewUp,
                 double aspect, double viewAngleDeg = 20.0, double margin = 1.1);
/// fitCamera on the points of one or more surfaces (pre and post together frame both).
Camera fitCamera(const std::vector<vtkPolyData*>& surfaces, const Eigen::Vector3d& toCamera,
                 const Eigen::Vector3d& viewUp, double aspect, double viewAngleDeg = 20.0, double margin = 1.1);

/// The camera of a view in the head's cylindrical frame: looking from frame.radialDirection(θ)
/// with view-up along the frame's axis (patient superior), fitted to the surfaces.
Camera headCamera(const seg::CylindricalFrame& frame, View view, const std::vector<vtkPolyData*>& surfaces,
                  double aspect, double viewAngleDeg = 20.0, double margin = 1.1);
/// The same with any θ (radians).
Camera headCamera(const seg::CylindricalFrame& frame, double theta, const std::vector<vtkPolyData*>& surfaces,
                  double aspect, double viewAngleDeg = 20.0, double margin = 1.1);
///@}

/// @name Rendering
///@{
/// Renders the figure offscreen (OffscreenDisplay::ensure() first) into an RGB unsigned char
/// image of figure.width × figure.height (VTK layout: row 0 at the bottom).
/// @throws std::invalid_argument for a bad size, a missing surface or array;
/// std::runtime_error when there is no display and no Xvfb.
vtkSmartPointer<vtkImageData> renderFigure(const Figure& figure);

/// Where a world point lands in the figure, in pixels from the top-left corner (x right, y down;
/// pixel (i, j) covers [i, i+1) × [j, j+1)). Uses the figure's camera and scene viewport.
Eigen::Vector2d projectToPixel(const Figure& figure, const Eigen::Vector3d& point);

/// Writes an RGB or RGBA unsigned char image as PNG. @throws std::runtime_error when it cannot.
void writePng(vtkImageData* image, const std::filesystem::path& path);

/// RGB bytes, rows top-down, 3·width bytes a row (what QImage::Format_RGB888 expects).
struct RgbBytes
{
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> bytes;
};
RgbBytes rgbBytesTopDown(vtkImageData* image);
/// The image as a QImage (Format_RGB888, owning its data).
QImage toQImage(vtkImageData* image);
///@}

/// @name Checks on rendered images
/// Pixel coordinates are top-down (row 0 at the top), as in rgbBytesTopDown.
///@{
/// The pixel's RGB at column x, row y from the top.
std::array<std::uint8_t, 3> pixelAt(vtkImageData* image, int x, int y);
/// Variance of the luminance (0–255 scale) over all pixels; 0 for a blank render.
double pixelVariance(vtkImageData* image);
/// Fraction of pixels differing from background by more than tolerance (0–255) in any channel.
double occupiedFraction(vtkImageData* image, const Rgb& background = {1.0, 1.0, 1.0}, int tolerance = 8);
/// Inclusive pixel box.
struct PixelBox
{
  int x0 = 0, y0 = 0, x1 = -1, y1 = -1;
  int width() const { return x1 - x0 + 1; }
  int height() const { return y1 - y0 + 1; }
};
/// The smallest box holding every non-background pixel, or nullopt when there is none.
std::optional<PixelBox> boundingBoxOfNonBackground(vtkImageData* image, const Rgb& background = {1.0, 1.0, 1.0},
                                                   int tolerance = 8);
///@}

} // namespace caps::render
