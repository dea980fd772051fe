#pragma once
/// @file PlanDisplay.h
/// @brief The display surfaces of a simulated plan (thesis §4.7): the skin
/// faces of the continuum mesh subdivided in body coordinates, with the
/// range detail of the scan, the skin's colour and the solution's
/// displacement, strain and stress, as VTK polydata and VTP files.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <vtkSmartPointer.h>

#include "fem/DisplaySurface.h"
#include "planning/PlanSimulation.h"
#include "segmentation/RangeMap.h"
#include "segmentation/SurfaceScanColourMap.h"

class vtkImageData;
class vtkPolyData;

namespace caps::planning {

/// Options of buildPlanDisplay().
struct PlanDisplayOptions
{
  /// Steps per element edge (§4.7: the user trades image quality against
  /// speed): n × n quadrilaterals per quadrilateral face, n² triangles per
  /// triangle.
  int resolution = 4;
  /// Add the range displacement (range detail) to every vertex, so the
  /// surface shows the scan at its own resolution instead of the quadratic
  /// element faces.
  bool rangeDetail = true;
  /// Longest range displacement kept (mm). Where the scan drops away between
  /// the nodes (a nostril, the fold under the nose) the ray from the axis
  /// meets the skin centimetres from the smooth element face; following it
  /// would draw spikes, so there the vertex stays on the face.
  double maxRangeDetail = 3.0;
  /// The undermined skin (thesis §3.2.4 item 2) is tinted (kUnderminedTint)
  /// with diagonal stripes this far apart (mm on the skin), denser on every
  /// other stripe like a hatch; 0: a plain tint.
  double underminingHatch = 4.0;
};

/// The colour the undermined skin is blended towards in skin_colour: a blue
/// no skin shade is near.
inline constexpr seg::Rgb8 kUnderminedTint = {40, 110, 255};

/// The skin of a simulated plan, ready to show.
struct PlanDisplay
{
  /// Subdivided skin faces (the top faces of the skin layer), in body
  /// coordinates, with the range detail and the prediction's solution set.
  fem::DisplaySurface surface;
  /// Source colour of each vertex (Table 4.9), read at its undeformed (θ, z)
  /// from the colour map given; seg::kNoSourceColour (grey) without one.
  std::vector<seg::Rgb8> skinShade;
  /// How undermined each vertex is, 0..1: the prediction's undermined
  /// surface-mesh vertices (PlanPrediction::underminedVertices: the band and
  /// the plan's regions) as 1 on their node columns, a mid-edge column the
  /// mean of its two ends, interpolated with the vertex's shape functions.
  /// So 1 over undermined skin, 0 where no undermined vertex is near, a ramp
  /// across the elements on the region's border.
  std::vector<double> undermined;
  /// How strongly skin_colour blends an undermined vertex towards
  /// kUnderminedTint (0..1): the hatch's stripes, times undermined.
  std::vector<double> underminingTint;
  /// Whether positions include the range detail (PlanDisplayOptions).
  bool rangeDetail = true;
  /// Vertices where the skin map has no surface (NaN): no range detail there.
  int verticesWithoutScan = 0;
  /// Vertices whose range displacement was longer than maxRangeDetail (left on the face).
  int verticesBeyondDetailLimit = 0;
  /// Largest range displacement (mm): how far the quadratic element faces
  /// stray from the scanned skin.
  double largestRangeDetail = 0.0;

  /// Vertex positions at displacement scale @a scale (0 before, 1 after the operation).
  Eigen::Matrix3Xd positions(double scale) const { return surface.positions({scale, rangeDetail}); }
};

/// The skin's shade for a display surface (Table 4.9's source colour): the
/// CT's, or why the skin is grey.
struct SkinShade
{
  std::optional<seg::ColourMap> colour; ///< empty: grey
  std::string note;                     ///< why the skin is grey; "" when it is not
  /// What buildPlanDisplay() takes: null for grey.
  const seg::ColourMap* map() const { return colour ? &*colour : nullptr; }
};

/// The shade of seg::skinShadeFromCt() on @a skin's frame, or, when there is
/// no CT (null) or its shade cannot be read, none and a note saying so for
/// the status line. Does not throw for the CT's sake.
SkinShade skinShadeOfCt(vtkImageData* ct, const seg::RangeMap& skin);

/// What setRangeDetail() left out.
struct RangeDetailCounts
{
  int verticesWithoutScan = 0;       ///< the map has no surface there (NaN)
  int verticesBeyondDetailLimit = 0; ///< the offset was longer than the limit
  double largestRangeDetail = 0.0;   ///< mm, of the offsets kept
};

/// @brief Sets the range detail of @a surface (Table 4.9's range
/// displacement, §4.7): the scanned skin point at each vertex's undeformed
/// (θ, z) (the skin map read bilinearly, eq. 4.9) minus the vertex; zero
/// where the map has no surface, and where it is longer than
/// @a maxRangeDetail (a nostril, the fold under the nose: see
/// PlanDisplayOptions::maxRangeDetail).
RangeDetailCounts setRangeDetail(fem::DisplaySurface& surface, const seg::RangeMap& skin, double maxRangeDetail);

/// @brief Builds the display surface of the skin of the operated region
/// (thesis §4.7) from a prediction.
///
/// The skin faces are the top faces of the continuum mesh's skin layer
/// (fem::skinFaces), subdivided at options.resolution. The range
/// displacement of a vertex is the scanned skin point at the vertex's
/// undeformed (θ, z) (the skin map read bilinearly, eq. 4.9) minus its
/// undeformed position on the quadratic face; it stays with the vertex
/// when the skin moves (the thesis adds it unchanged in the deformed state).
/// Where the map has no surface the offset is zero (counted in
/// verticesWithoutScan).
///
/// @param skin    the skin range map the plan was simulated on.
/// @param colour  the skin's colour on a cylindrical frame: a surface scan's
///                colour channel (seg::SurfaceScan::colour), or for a CT the
///                shade of seg::skinShadeFromCt(); null for grey.
/// Where the skin map drops away between the nodes (a nostril, the fold
/// under the nose) the range detail would be centimetres long (on the sample
/// CT's Z-plasty at (-90°, 0) most offsets are a tenth of a millimetre, a
/// few 15–48 mm under the nose): offsets beyond options.maxRangeDetail are
/// left out (counted in verticesBeyondDetailLimit).
/// @throws std::invalid_argument for a resolution below 1 or an empty skin map.
PlanDisplay buildPlanDisplay(const PlanPrediction& prediction, const seg::RangeMap& skin,
                             const seg::ColourMap* colour = nullptr, const PlanDisplayOptions& options = {});

/// @brief The display surface at displacement scale @a scale (0: before the
/// operation, 1: after) as polydata (mm, patient LPS; polygons outward).
///
/// Point data: displacement_mm (3), displacement_magnitude_mm,
/// von_mises_kPa, mean_stress_kPa (the thesis's pressure stress with the
/// opposite sign), stress_kPa (6, Voigt xx yy zz xy yz zx), strain (6,
/// engineering shear), equivalent_strain (von Mises), volumetric_strain
/// (the thesis's pressure strain), range_detail_mm (3), skin_shade (RGB,
/// unsigned char: the source colour), undermined (0..1, PlanDisplay::undermined),
/// skin_colour (RGB, unsigned char: skin_shade blended towards
/// kUnderminedTint by PlanDisplay::underminingTint, the undermined skin
/// hatched; the active scalars), element and rst (the body coordinates). Field data: displacement_scale, resolution, range_detail.
/// Displacement, strain and stress are those of the full solution whatever
/// the scale.
vtkSmartPointer<vtkPolyData> planDisplayPolyData(const PlanDisplay& display, double scale);

/// The wound as cut, gaping under the skin's pre-tension before it is
/// sutured (PlanPrediction::gape): @a display's surface under the gape's
/// displacements, the middle step of intact → gaping → closed. Null when
/// the prediction has no gape or its solve did not converge.
vtkSmartPointer<vtkPolyData> gapingSkinPolyData(const PlanDisplay& display, const PlanPrediction& prediction);

/// Writes the surface before (scale 0) and after (scale 1) the operation as
/// VTK XML PolyData. @throws std::runtime_error naming a file that cannot be written.
void writePlanDisplay(const PlanDisplay& display, const std::filesystem::path& before,
                      const std::filesystem::path& after);

} // namespace caps::planning
