#pragma once
/// @file IncisionPlan.h
/// @brief The plan drawn on the skin: the cut path, the hole it makes
/// (Fig. 4.11), the excision offsets (§4.4.4) and the sutures (§4.4.5).

#include <array>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "fem/SurfaceMesh.h"
#include "planning/SkinChart.h"

namespace caps::planning {

/// @name The hole loop of a cut path (Fig. 4.11)
/// The cut path p0..p(n-1) becomes the loop p0, p1, ..., p(n-1), p(n-2)', ...,
/// p1': loop vertex i (0 ≤ i < n) is pi on the left side of the cut (seen
/// from outside the head, walking from p0 to p(n-1)) and loop vertex
/// 2(n-1) − i is its twin pi' on the right side. The skin lies to the left of
/// every loop edge (i, i+1), as fem/SurfaceMesh.h requires: opening the cut
/// moves left-side points further left and right-side points further right.
///@{
/// 2(n − 1) border vertices for n ≥ 2 path points.
int holeLoopSize(int pathPoints);
/// The loop vertex of cut point i on the right side of the cut (i itself for the two ends).
int rightSideVertex(int pathIndex, int pathPoints);
/// The cut point a loop vertex came from.
int pathIndexOfVertex(int loopVertex, int pathPoints);
/// The hole loop of a cut path drawn in the chart; offsets (one per loop
/// vertex, or empty) move border points away from their twins (§4.4.4).
fem::HoleLoop makeHoleLoop(const std::vector<ChartPoint>& path, const std::vector<ChartPoint>& offsets = {});
///@}

/// Two border edges to sew together as the thesis writes them (§4.4.5),
/// each as two loop vertex indices in either direction:
/// "((0,1),(0,5))" is {{0, 1}, {0, 5}}.
struct SutureEdges
{
  std::array<int, 2> a{};
  std::array<int, 2> b{};
  bool operator==(const SutureEdges& o) const { return a == o.a && b == o.b; }
};

/// A suture set that cannot close the hole; suture() is the 0-based index of
/// the offending pair (-1 when the whole set is at fault).
class SutureError : public std::invalid_argument
{
public:
  SutureError(int suture, const std::string& message) : std::invalid_argument(message), suture_(suture) {}
  int suture() const { return suture_; }

private:
  int suture_;
};

/// Turns written suture pairs into fem::SutureEdgePair (a0 onto b0, a1 onto b1).
///
/// Two pieces of skin sewn together meet face to face, so the loop-order
/// start of one edge goes onto the loop-order end of the other, whatever
/// order the edges were written in. This is the rule behind the thesis's
/// examples: the simple excision's ((1,2),(5,4)) sews 1 to 5 and 2 to 4, and
/// the Z-plasty's ((0,1),(3,4)) sews 0 to 4 and 1 to 3 (the two corner
/// sutures ((5,0),(5,4)) and ((2,1),(2,3)) already bring 0 to 4 and 1 to 3).
/// A shared vertex is a corner being closed and gets no suture (corner rule).
///
/// @throws SutureError when an edge is not a border edge of a loop of
/// loopSize vertices, an edge is sewn twice or to itself, or the sutures
/// together would pull the two ends of a border edge onto one point.
std::vector<fem::SutureEdgePair> resolveSutures(int loopSize, const std::vector<SutureEdges>& written);

/// The loop vertices each vertex is sewn onto (itself included), from
/// resolved sutures: the points that coincide after closure.
std::vector<std::vector<int>> sutureClasses(int loopSize, const std::vector<fem::SutureEdgePair>& sutures);

/// A closed polygon on the skin, points (θn, zn) in normalised cylindrical
/// coordinates (§4.2.2); the last point joins the first.
using UnderminedRegion = std::vector<Eigen::Vector2d>;

/// How deep a procedure cuts (thesis §3.2.2: cutting to a depth) and so the
/// plane its undermined tissue is raised in and slides on.
enum class CutDepth
{
  /// Through every layer to the bone, raised on the periosteum: the
  /// thesis's model (§4.5.2).
  Bone,
  /// Through the skin and the subcutaneous layers, raised on the deep
  /// fascia / SMAS: every layer of the model but the deepest, which stays
  /// whole on the bone. How facial flaps are raised.
  Fascia,
};

/// "bone" or "fascia": the name in procedure files, scenes and plan.json.
const char* cutDepthId(CutDepth depth);
/// The depth of an id of cutDepthId(); empty for any other text.
std::optional<CutDepth> cutDepthFromId(const std::string& id);
/// The layers a cut to @a depth goes through in a model of @a layerCount layers.
int layersCutTo(CutDepth depth, int layerCount);

class IncisionPlan;

/// The name on the renders of hole-loop vertex @a loopVertex of a cut of
/// @a pathPoints points: "p2" on the left of the cut, "p2'" its twin on the right.
std::string cutPointName(int loopVertex, int pathPoints);

/// The wound line suture @a suture of @a plan closes: the procedure's own
/// words (IncisionPlan::woundLineNames()), else its edges by cut point
/// ("p0-p1 onto p1'-p0").
std::string woundLineName(const IncisionPlan& plan, int suture);

/// @class IncisionPlan
/// @brief A surgical plan on one skin range map: the cut path in normalised
/// cylindrical coordinates (§4.2.2), excision offsets and sutures.
///
/// The plan is a value: copy it before an edit that may be refused to keep
/// the previous plan. Geometry in millimetres comes from chart(skin), the
/// local chart about centre().
class IncisionPlan
{
public:
  IncisionPlan() = default;
  /// A cut path (θn, zn) with its chart centre (θ, z); no offsets, no sutures.
  IncisionPlan(std::vector<Eigen::Vector2d> cutPath, SkinPoint centre);

  /// "z-plasty", "elliptical-excision", ...; empty for a hand-drawn cut.
  const std::string& procedure() const { return procedure_; }
  void setProcedure(std::string procedure) { procedure_ = std::move(procedure); }
  /// The cut generator of the procedure ("z", "ellipse", ...; ProcedureTemplate).
  const std::string& generator() const { return generator_; }
  void setGenerator(std::string generator) { generator_ = std::move(generator); }
  /// Parameter values the template was placed with (mm, radians, ratios).
  const std::map<std::string, double>& parameters() const { return parameters_; }
  void setParameters(std::map<std::string, double> parameters) { parameters_ = std::move(parameters); }

  /// Cut points (θn, zn) in [-1, 1]², in the order the scalpel runs.
  const std::vector<Eigen::Vector2d>& cutPath() const { return cutPath_; }
  int pointCount() const { return int(cutPath_.size()); }
  /// Moves cut point i (both sides of the cut move; their offsets stay).
  /// @throws std::out_of_range when i is not a cut point.
  void moveCutPoint(int i, const Eigen::Vector2d& thetaZN);

  /// The chart centre: where the template was placed, or the path's middle.
  const SkinPoint& centre() const { return centre_; }
  void setCentre(const SkinPoint& c) { centre_ = c; }
  /// The chart about centre() on this skin map.
  SkinChart chart(const seg::RangeMap& skin) const { return SkinChart(skin, centre_.theta, centre_.z); }

  /// Excision (§4.4.4): border vertex v is moved by d (chart mm) away from
  /// its twin. Only the two sides of an inner cut point can be separated;
  /// d = 0 puts the point back on the cut.
  /// @throws std::out_of_range for a vertex not on the border, std::invalid_argument for an end of the cut.
  void offsetBorderPoint(int loopVertex, const ChartPoint& d);
  /// Offsets of every loop vertex (zero where none), holeLoopSize() long.
  std::vector<ChartPoint> borderOffsets() const;
  bool isExcision() const;

  /// Sutures as written (thesis notation) and resolved for the mesher.
  const std::vector<SutureEdges>& writtenSutures() const { return written_; }
  const std::vector<fem::SutureEdgePair>& sutures() const { return sutures_; }
  /// @throws SutureError (see resolveSutures); the plan keeps its old sutures then.
  /// @a woundLineNames: per written suture, the wound line it closes
  /// (ProcedureTemplate::woundLineNames()), or empty.
  /// @throws std::invalid_argument when names are given but not one per suture.
  void setSutures(std::vector<SutureEdges> written, std::vector<std::string> woundLineNames = {});
  /// Per written suture, the wound line it closes in the surgeon's words;
  /// woundLineName() gives one for every suture.
  const std::vector<std::string>& woundLineNames() const { return woundLineNames_; }

  /// The band along the sutured edges the procedure undermines by default
  /// (mm on the skin; ProcedureTemplate, DefaultUndermining), 0 for a
  /// hand-drawn cut; SimulationOptions::underminingWidth, when the surgeon
  /// sets it, replaces it (underminingWidthFor()).
  double underminingBand() const { return underminingBand_; }
  /// @throws std::invalid_argument for a negative or non-finite width.
  void setUnderminingBand(double millimetres);

  /// How deep the procedure cuts and where it raises what it undermines
  /// (CutDepth); the thesis's full thickness for a hand-drawn cut.
  /// SimulationOptions::cutLayers, when the surgeon sets it, replaces it
  /// (cutLayersFor()).
  CutDepth cutDepth() const { return cutDepth_; }
  void setCutDepth(CutDepth depth) { cutDepth_ = depth; }

  /// @name Undermined regions (thesis §3.2.2, §3.2.4 item 2)
  /// Regions of skin the surgeon frees from what lies beneath, besides the
  /// band along the sutured edges (underminingBand()):
  /// closed polygons of points (θn, zn) in normalised cylindrical
  /// coordinates like the cut path, the last point joined to the first. The
  /// undermined skin is their union. Undermining.h checks them and finds the
  /// mesh vertices inside; the plan only keeps them.
  ///@{
  const std::vector<UnderminedRegion>& underminedRegions() const { return underminedRegions_; }
  void addUnderminedRegion(UnderminedRegion region) { underminedRegions_.push_back(std::move(region)); }
  void clearUnderminedRegions() { underminedRegions_.clear(); }
  ///@}

  /// The cut path in the chart (mm).
  std::vector<ChartPoint> chartPath(const SkinChart& chart) const;
  /// The hole loop (Fig. 4.11) in the chart, offsets applied.
  fem::HoleLoop holeLoop(const SkinChart& chart) const;

private:
  std::string procedure_;
  std::string generator_;
  std::map<std::string, double> parameters_;
  std::vector<Eigen::Vector2d> cutPath_;
  SkinPoint centre_;
  std::map<int, ChartPoint> offsets_;
  std::vector<SutureEdges> written_;
  std::vector<fem::SutureEdgePair> sutures_;
  std::vector<std::string> woundLineNames_;
  std::vector<UnderminedRegion> underminedRegions_;
  double underminingBand_ = 0.0;
  CutDepth cutDepth_ = CutDepth::Bone;
};

/// Checks a plan can be cut on this skin: at least two cut points, no two
/// neighbours closer than minSpacing (mm, on the chart), no crossing limbs,
/// excision sides not swapped (the hole runs clockwise, as fem/SurfaceMesh.h
/// needs), and measured skin under every point and limb.
/// @throws std::invalid_argument naming the cut point or limb at fault.
void checkPlan(const IncisionPlan& plan, const seg::RangeMap& skin, double minSpacing = 0.5);

} // namespace caps::planning
