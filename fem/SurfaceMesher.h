#pragma once
/// @file SurfaceMesher.h
/// @brief Grows triangles and quadrilaterals out from an incision's hole loop
/// in the skin chart (thesis §4.5.1), and checks the result.

#include "fem/SurfaceMesh.h"

#include <limits>
#include <numbers>
#include <string>
#include <vector>

namespace caps::fem {

/// Shape limits every polygon of a surface mesh must meet (angles in radians).
/// The mesher refuses to emit polygons outside them; surfaceMeshQuality()
/// reports polygons that are.
struct MeshQualityLimits
{
  double minAngle = 15.0 * std::numbers::pi / 180.0;
  double maxAngle = 165.0 * std::numbers::pi / 180.0;
  /// Longest edge squared over area, scaled so an equilateral triangle and a
  /// square are 1 (a 3 x 1 rectangle is 3).
  double maxAspectRatio = 8.0;
};

/// Parameters of the surface mesher. Lengths in mm of the chart, angles in
/// radians.
struct SurfaceMesherOptions
{
  /// t1 (§4.5.1): stage 1 fills border concavities turning more than this with
  /// a triangle. Thesis default 30°.
  double triangleFillAngle = 30.0 * std::numbers::pi / 180.0;
  /// t2 (§4.5.1): a border vertex whose hole-side angle is below this (the
  /// border turns convexly by more than 180° − t2) is "expanded": stage 2 adds
  /// corner quadrilaterals there. Thesis default 90°.
  double cornerExpandAngle = 90.0 * std::numbers::pi / 180.0;
  /// l1: thickness of the first quadrilateral layer, the element size at the
  /// wound. 0: the median hole edge length, kept between a quarter of the
  /// longest hole edge and 3 times the shortest. Hole edges must lie between
  /// l1 / 3 and 4 l1 (see refineCutPath).
  double firstLayerThickness = 0.0;
  /// Each layer is this many times thicker than the one inside it, so the
  /// region reaches well beyond the wound while elements at the wound stay
  /// small. 1 gives the thesis's equal layers.
  double layerGrowth = 1.25;
  /// Number of quadrilateral layers (used when regionRadius is 0).
  int layerCount = 4;
  /// When > 0: as many layers as needed for their thicknesses to add up to
  /// this distance from the (stage-1 filled) hole to the rim, all scaled by
  /// one factor so they add up exactly.
  double regionRadius = 0.0;
  /// The scanned range in the chart's v (bottom and top). The mesh never
  /// leaves it: where a layer reaches a bound its new vertices are put on the
  /// bound and stop growing there.
  double vMin = -std::numeric_limits<double>::infinity();
  double vMax = std::numeric_limits<double>::infinity();
  /// Cut points (and separate parts of the hole border) closer than this are
  /// refused: the surgeon is asked to move them apart.
  double minPointSpacing = 1.0;
  MeshQualityLimits quality;
};

/// Counts and shape statistics of a surface mesh, and what is wrong with it.
struct SurfaceMeshQuality
{
  int vertexCount = 0;
  int triangleCount = 0;
  int quadCount = 0;
  double minAngle = 0.0;       ///< smallest polygon corner angle (rad)
  double maxAngle = 0.0;       ///< largest polygon corner angle (rad)
  double maxAspectRatio = 0.0; ///< as in MeshQualityLimits
  double meshArea = 0.0;       ///< sum of polygon areas (mm²)
  double holeArea = 0.0;       ///< area inside the hole loop (0 for a cut)
  double outerArea = 0.0;      ///< area inside the outer border
  /// One line per problem found (first few of each kind); empty = valid.
  std::vector<std::string> problems;
  bool valid() const { return problems.empty(); }
};

/// What meshAroundHole() built, and why it stopped where it did.
struct SurfaceMesherResult
{
  SurfaceMesh mesh;
  int stageOneTriangles = 0; ///< triangles stage 1 added to the hole (Fig. 4.13's 1 and 2)
  int layersPlanned = 0;
  int layersBuilt = 0;
  double reach = 0.0;             ///< summed thickness of the layers built (mm)
  bool reachedChartBound = false; ///< part of the rim lies on vMin or vMax
  bool stoppedEarly = false;      ///< fewer layers than planned (see message)
  /// Empty when all went as planned; otherwise a sentence for the surgeon.
  std::string message;
  SurfaceMeshQuality quality;
};

/**
 * @brief The hole loop of an incision (Fig. 4.11): cut path p0..p(n-1)
 *        becomes p0, p1, ..., p(n-1), p(n-2)', ..., p1'.
 *
 * The first copies lie on the left of the cut direction and the twins (')
 * on its right, which makes the loop clockwise around the hole as
 * SurfaceMesh.h requires; an excision (§4.4.4) therefore moves points to
 * the left and twins to the right of the cut. Throws std::invalid_argument
 * for fewer than 2 points.
 */
HoleLoop holeLoopFromCutPath(const std::vector<ChartPoint>& cutPath);

/// A cut path with points added along long segments.
struct RefinedCutPath
{
  std::vector<ChartPoint> points;
  /// For each point of the original path, its index in points.
  std::vector<int> originalIndex;
};

/// Splits every segment of @a cutPath longer than @a maxSpacing into equal
/// parts no longer than it, so that elements at the wound can be small
/// (the hole's edges are element edges).
RefinedCutPath refineCutPath(const std::vector<ChartPoint>& cutPath, double maxSpacing);

/**
 * @brief Meshes the skin around @a hole (thesis §4.5.1).
 *
 * Stage 1 fills border concavities turning by more than t1 with triangles
 * (v_i, v_i+1, v_i+2) until the region is nearly convex; stage 2 offsets the
 * border by one layer of quadrilaterals per pass, one per border edge plus
 * corner quadrilaterals at "expanded" vertices (convex turn > 180° − t2).
 * Beyond the thesis: stage 1 only adds well-shaped triangles (it runs again
 * before every layer); a 180° turn (the end of a cut, where twins meet) gets
 * two corner quadrilaterals; new border edges that grow too long are split
 * (a quadrilateral and a triangle) and ones that shrink too short, at
 * concave corners or as layers thicken, are merged (a triangle); layers
 * stop at the chart bounds; every layer is checked (shape limits, no overlap
 * with anything already meshed) and, if it fails, retried after filling all
 * concavities and then at half thickness before meshing stops with a message.
 *
 * Throws std::invalid_argument, with a message naming the cut points, when
 * the hole cannot be meshed as given (points too close, the cut crossing or
 * nearly touching itself, turning back too sharply, leaving the scanned
 * range, the loop wound the wrong way).
 */
SurfaceMesherResult meshAroundHole(const HoleLoop& hole, const SurfaceMesherOptions& options = {});

/**
 * @brief Checks @a mesh and measures it.
 *
 * Every polygon must be counter-clockwise with positive area, convex, with
 * its angles and aspect ratio inside @a limits; no two polygons may overlap
 * (checked through a uniform grid); every polygon edge must be shared by
 * exactly two polygons unless it is a hole-loop or outer-border edge, which
 * must be used once; and the polygons must cover the region between hole and
 * rim: sum of areas = area inside outer border − hole area.
 */
SurfaceMeshQuality surfaceMeshQuality(const SurfaceMesh& mesh, const MeshQualityLimits& limits = {});

} // namespace caps::fem
