#include "planning/PlanSimulation.h"

#include <algorithm>
#include <map>
#include <chrono>
#include <cmath>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <Eigen/Geometry>

#include "fem/DisplaySurface.h"
#include "fem/FiniteStrainStress.h"
#include "fem/InitialStress.h"
#include "fem/StaticAnalysis.h"
#include "planning/SkinTensionLines.h"
#include "planning/Undermining.h"
#include "segmentation/LandmarkPlacement.h"

namespace caps::planning {
namespace {

constexpr double pi = 3.14159265358979323846;
constexpr double degrees = 180.0 / pi;

double secondsSince(std::chrono::steady_clock::time_point start)
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

int findRoot(std::vector<int>& parent, int i)
{
  while (parent[i] != i)
    i = parent[i] = parent[parent[i]];
  return i;
}

/// Cut segment (path index of its first point) of loop edge (v, w).
int segmentOfEdge(int v, int w, int pathPoints)
{
  return std::min(pathIndexOfVertex(v, pathPoints), pathIndexOfVertex(w, pathPoints));
}

std::string where(const SkinChart& chart, const ChartPoint& c)
{
  const SkinPoint s = chart.fromChart(c);
  std::ostringstream out;
  out << "chart (" << c.x() << ", " << c.y() << ") mm, θ = " << s.theta * degrees << "°, z = " << s.z << " mm";
  return out.str();
}

void checkOptions(const SimulationOptions& o)
{
  auto bad = [](const std::string& what) { throw std::invalid_argument("simulation options: " + what); };
  if (!(o.elementSize > 0.0) || !std::isfinite(o.elementSize))
    bad("the element size must be a positive number of mm");
  if (!(o.regionRadius > 0.0) || !std::isfinite(o.regionRadius))
    bad("the region radius must be a positive number of mm");
  if (!(o.layerGrowth >= 1.0) || !std::isfinite(o.layerGrowth))
    bad("the layer growth must be at least 1");
  if (o.layerCount < 1)
    bad("at least one element layer is needed from the skin to the bone");
  if (!(o.minDepth > 0.0) || !(o.maxDepth >= o.minDepth) || !std::isfinite(o.maxDepth))
    bad("the depth limits must satisfy 0 < minDepth <= maxDepth");
  if (!(o.noBoneDepth > 0.0) || !std::isfinite(o.noBoneDepth))
    bad("the depth used where there is no bone must be positive");
  if (o.threads < 1)
    bad("at least one thread");
  if (o.preTension)
    o.preTension->validate();
  if (o.underminingWidth && (!(*o.underminingWidth >= 0.0) || !std::isfinite(*o.underminingWidth)))
    bad("the undermining width must be 0 (none) or a positive number of mm");
  if (o.cutLayers && (*o.cutLayers < 0 || *o.cutLayers > o.layerCount))
    bad("the cut goes through " + std::to_string(*o.cutLayers) + " layers of " + std::to_string(o.layerCount) +
        ": give 1.." + std::to_string(o.layerCount) + ", or 0 for full thickness");
}

} // namespace

// Default soft-tissue materials.
//
// Linear isotropic elasticity is a small-strain simplification of tissue
// that is in fact hyperelastic and viscoelastic; the values below are
// ASSUMPTIONS of the order of magnitude used by published finite element
// models of the face, not measurements of this patient; the exact values in
// the papers below are still to be confirmed against them:
//  - single-material linear face models use E of a few to tens of kPa with
//    ν ≈ 0.45–0.49 (Chabanas, Luboz & Payan, "Patient specific finite element
//    model of the face soft tissues for computer-assisted maxillofacial
//    surgery", Med. Image Anal. 7(2), 2003; Keeve et al., "Deformable
//    modeling of facial tissue for craniofacial surgery simulation", Comput.
//    Aided Surg. 3, 1998);
//  - layered models give skin (dermis) the stiffest layer, of the order of
//    0.1 MPa at small strain, fat the softest (a few kPa) and muscle / SMAS
//    in between (Barbarino, Jabareen, Trzewik, Nkengne, Stamatas & Mazza,
//    "Development and validation of a three-dimensional finite element model
//    of the face", J. Biomech. Eng. 131(4), 2009; Mazza & Barbarino, "3D
//    mechanical modeling of facial soft tissue for surgery simulation",
//    Facial Plast. Surg. Clin. N. Am. 19(4), 2011).
// We take skin E = 0.15 MPa, fat 0.01 MPa, muscle 0.05 MPa and ν = 0.45
// everywhere (nearly incompressible but far enough from 0.5 that quadratic
// elements do not lock). A suture-driven solve without loads gives
// displacements that depend only on the ratios of the moduli and on ν.
// Density ≈ that of water (1e-9 t/mm³), used only by gravity loads.
fem::MaterialTable defaultFacialTissueMaterials(int layerCount)
{
  static const double modulus[] = {0.15, 0.01, 0.05};
  fem::MaterialTable table;
  for (int layer = 0; layer < std::max(layerCount, 1); ++layer)
    table[layer] = fem::LinearElasticMaterial{modulus[std::min(layer, 2)], 0.45, 1.0e-9};
  return table;
}

fem::ContinuumMeshOptions TissueDepthOptions::continuumMeshOptions() const
{
  fem::ContinuumMeshOptions out;
  out.layerCount = layerCount;
  out.layerFractions = layerFractions;
  out.minDepth = minDepth;
  out.maxDepth = maxDepth;
  out.noBoneDepth = noBoneDepth;
  return out;
}

fem::MaterialTable TissueDepthOptions::layerMaterials() const
{
  return materials.empty() ? defaultFacialTissueMaterials(layerCount) : materials;
}

seg::RangeMap boneForTissueDepth(const seg::RangeMap& skin, const seg::RangeMap& bone, double noBoneDepth,
                                 int smoothingPasses)
{
  // Holes filled at the default depth under the skin, then smoothed so
  // neighbouring columns do not jump (a jump of a centimetre between 2 mm
  // columns folds the deep elements).
  seg::RangeMap out = bone;
  if (bone.empty() || smoothingPasses <= 0)
    return out;
  const seg::CylindricalFrame& bf = bone.frame();
  for (int j = 0; j < bf.nZ(); ++j)
    for (int i = 0; i < bf.nTheta(); ++i)
      if (!std::isfinite(out.at(i, j)))
      {
        const double rSkin = skin.sample(bf.indexToTheta(i), bf.indexToZ(j));
        if (std::isfinite(rSkin))
          out.at(i, j) = float(rSkin - noBoneDepth);
      }
  for (int pass = 0; pass < smoothingPasses; ++pass)
    out = seg::boxSmooth(out);
  return out;
}

fem::TissueGeometry skinToBoneGeometry(const SkinChart& chart, const seg::RangeMap& skin,
                                       const seg::RangeMap& boneForDepth)
{
  fem::TissueGeometry geometry;
  geometry.skinPoint = [&chart](const ChartPoint& c) { return chart.lift(c); };
  geometry.inwardDirection = [&chart, &skin](const ChartPoint& c) -> Eigen::Vector3d {
    return -skin.frame().radialDirection(chart.fromChart(c).theta);
  };
  geometry.tissueDepth = [&chart, &skin, &boneForDepth](const ChartPoint& c) {
    const SkinPoint s = chart.fromChart(c);
    const double rSkin = skin.sample(s.theta, s.z);
    const double rBone = boneForDepth.empty() ? std::nan("") : boneForDepth.sample(s.theta, s.z);
    return rSkin - rBone; // NaN where there is no bone: noBoneDepth
  };
  return geometry;
}

Eigen::Vector3d PlanPrediction::displacedNode(int i) const
{
  return continuum.mesh.nodes.col(i) + displacements.segment<3>(3 * Eigen::Index(i));
}

RefinedHole refineHole(const std::vector<ChartPoint>& path, const std::vector<ChartPoint>& offsets,
                       const std::vector<fem::SutureEdgePair>& sutures, double maxSpacing)
{
  const int n = int(path.size());
  if (n < 2)
    throw std::invalid_argument("a cut needs at least two points");
  if (!(maxSpacing > 0.0))
    throw std::invalid_argument("the element size at the wound must be positive");
  const int loop = holeLoopSize(n);
  if (!offsets.empty() && int(offsets.size()) != loop)
    throw std::invalid_argument("one border offset per hole-loop vertex is needed");
  auto offsetOf = [&](int v) { return offsets.empty() ? ChartPoint(0, 0) : offsets[v]; };
  auto position = [&](int v) -> ChartPoint { return path[pathIndexOfVertex(v, n)] + offsetOf(v); };

  // Border length of each segment (the longer of its two sides), and groups
  // of segments tied by sutures: sutured edges must be cut into as many pieces.
  const int segments = n - 1;
  std::vector<double> length(segments, 0.0);
  for (int v = 0; v < loop; ++v)
  {
    const int w = (v + 1) % loop;
    const int s = segmentOfEdge(v, w, n);
    length[s] = std::max(length[s], (position(w) - position(v)).norm());
  }
  std::vector<int> parent(segments);
  std::iota(parent.begin(), parent.end(), 0);
  auto checkEdge = [&](const std::array<int, 2>& e) {
    if (e[0] < 0 || e[0] >= loop || e[1] < 0 || e[1] >= loop ||
        !(e[1] == (e[0] + 1) % loop || e[0] == (e[1] + 1) % loop))
      throw std::invalid_argument("suture edge (" + std::to_string(e[0]) + "," + std::to_string(e[1]) +
                                  ") is not a border edge of the hole loop");
  };
  for (const auto& s : sutures)
  {
    checkEdge(s.a);
    checkEdge(s.b);
    const int ra = findRoot(parent, segmentOfEdge(s.a[0], s.a[1], n));
    const int rb = findRoot(parent, segmentOfEdge(s.b[0], s.b[1], n));
    parent[ra] = rb;
  }
  std::vector<int> groupPieces(segments, 1);
  for (int s = 0; s < segments; ++s)
  {
    const int r = findRoot(parent, s);
    groupPieces[r] = std::max(groupPieces[r], int(std::ceil(length[s] / maxSpacing - 1e-9)));
  }
  RefinedHole out;
  out.piecesPerSegment.resize(segments);
  for (int s = 0; s < segments; ++s)
    out.piecesPerSegment[s] = groupPieces[findRoot(parent, s)];

  // Refined path and where the original points went.
  std::vector<ChartPoint> points;
  std::vector<int> originalIndex(n);
  std::vector<int> segmentOf;   // per refined point: its segment
  std::vector<double> fraction; // and its place on it
  for (int s = 0; s < segments; ++s)
  {
    originalIndex[s] = int(points.size());
    const int k = out.piecesPerSegment[s];
    for (int i = 0; i < k; ++i)
    {
      const double t = double(i) / k;
      points.push_back(path[s] + t * (path[s + 1] - path[s]));
      segmentOf.push_back(s);
      fraction.push_back(t);
    }
  }
  originalIndex[n - 1] = int(points.size());
  points.push_back(path[n - 1]);
  segmentOf.push_back(segments - 1);
  fraction.push_back(1.0);
  const int m = int(points.size());
  const int refinedLoop = holeLoopSize(m);

  // Offsets interpolated along each side.
  std::vector<ChartPoint> refinedOffsets(refinedLoop, ChartPoint(0, 0));
  for (int k = 1; k + 1 < m; ++k)
  {
    const int s = segmentOf[k];
    const double t = fraction[k];
    auto left = [&](int p) { return offsetOf(p); };
    auto right = [&](int p) { return offsetOf(rightSideVertex(p, n)); };
    refinedOffsets[k] = (1 - t) * left(s) + t * left(s + 1);
    refinedOffsets[rightSideVertex(k, m)] = (1 - t) * right(s) + t * right(s + 1);
  }
  out.hole = makeHoleLoop(points, refinedOffsets);

  out.refinedVertexOf.resize(loop);
  for (int v = 0; v < loop; ++v)
  {
    const int k = originalIndex[pathIndexOfVertex(v, n)];
    out.refinedVertexOf[v] = v < n ? k : rightSideVertex(k, m);
  }

  // Each sutured edge walked along the refined loop, piece by piece.
  auto walk = [&](const std::array<int, 2>& e) {
    const int step = e[1] == (e[0] + 1) % loop ? 1 : -1;
    std::vector<int> seq{out.refinedVertexOf[e[0]]};
    const int end = out.refinedVertexOf[e[1]];
    while (seq.back() != end && int(seq.size()) <= refinedLoop)
      seq.push_back((seq.back() + step + refinedLoop) % refinedLoop);
    return seq;
  };
  for (const auto& s : sutures)
  {
    const std::vector<int> a = walk(s.a), b = walk(s.b);
    if (a.size() != b.size())
      throw std::logic_error("refineHole: sutured edges were refined into different numbers of pieces");
    for (std::size_t t = 0; t + 1 < a.size(); ++t)
      out.sutures.push_back({{a[t], a[t + 1]}, {b[t], b[t + 1]}});
  }
  return out;
}

namespace {

/// The plan's model from the cut to the closure (thesis §4.5), one step per
/// method: run() is the table of contents. simulatePlan() runs every step;
/// meshPlan() stops after the meshes.
class PlanModel
{
public:
  PlanModel(const seg::RangeMap& skin, const seg::RangeMap& bone, const IncisionPlan& plan,
            const SimulationOptions& options)
    : skin_(skin), bone_(bone), plan_(plan), options_(options), chart_(checkedChart(skin, bone, plan, options))
  {}

  PlanPrediction run(bool meshOnly)
  {
    phase(0.0, "Surface mesh around the plan");
    const auto meshStart = std::chrono::steady_clock::now();
    refineTheCut();
    meshTheSkin();
    phase(0.1, "Continuum mesh from the skin to the bone");
    meshTheTissue();
    out_.times.mesh = secondsSince(meshStart);
    checkTheThesisCounts();
    if (meshOnly)
      return std::move(out_);
    layerMaterials();
    preStressTheSkin();
    if (options_.model == TissueModel::LargeDeformation)
    {
      gapeInLargeDeformation();
      solveInLargeDeformation();
    }
    else
    {
      gapeLinear();
      solveLinear();
    }
    checkTheDeformation();
    stateTheMeshQuality();
    phase(0.9, "Closure forces");
    closureForces();
    skinForTheDisplay();
    zPlastyGain();
    return std::move(out_);
  }

private:
  /// The plan's chart on the skin, after checking the inputs (throws naming
  /// what is wrong: options, an empty map, no cut, maps on other axes).
  static SkinChart checkedChart(const seg::RangeMap& skin, const seg::RangeMap& bone, const IncisionPlan& plan,
                                const SimulationOptions& options)
  {
    checkOptions(options);
    if (skin.empty())
      throw std::invalid_argument("the skin range map is empty: build it from the CT first");
    if (plan.pointCount() < 2)
      throw std::invalid_argument("the plan has no cut (fewer than two cut points)");
    if (!options.layerFractions.empty() && int(options.layerFractions.size()) != options.layerCount)
      throw std::invalid_argument("simulation options: one layer fraction per layer is needed");
    const seg::CylindricalFrame& frame = skin.frame();
    if (options.boneSmoothingPasses < 0)
      throw std::invalid_argument("the bone smoothing passes must be 0 or more");
    if (!bone.empty() && ((bone.frame().origin() - frame.origin()).norm() > 1e-6 ||
                          (bone.frame().direction() - frame.direction()).norm() > 1e-9))
      throw std::invalid_argument("the bone range map is on another cylinder axis than the skin map: "
                                  "build both on the same frame");
    SkinChart chart = plan.chart(skin); // throws when the centre is off the skin
    checkPlan(plan, skin);
    return chart;
  }

  /// Between steps only: a step, once started, runs to its end.
  void phase(double fraction, const std::string& step) const { seg::reportProgress(options_.progress, fraction, step); }

  /// 1. The hole, refined to the element size consistently with the sutures.
  void refineTheCut()
  {
    refined_ = refineHole(plan_.chartPath(chart_), plan_.borderOffsets(), plan_.sutures(), options_.elementSize);
    out_.hole = refined_.hole;
    out_.sutures = refined_.sutures;
    out_.refinedVertexOf = refined_.refinedVertexOf;
  }

  /// 2. The surface mesh in the chart (§4.5.1), inside the scanned z range,
  /// with measured skin under every vertex and edge midpoint.
  void meshTheSkin()
  {
    fem::SurfaceMesherOptions surfaceOptions;
    surfaceOptions.firstLayerThickness = options_.elementSize;
    surfaceOptions.layerGrowth = options_.layerGrowth;
    surfaceOptions.regionRadius = options_.regionRadius;
    const auto [vMin, vMax] = scannedRows();
    surfaceOptions.vMin = vMin;
    surfaceOptions.vMax = vMax;
    surfaceOptions.minPointSpacing = std::min(1.0, 0.4 * options_.elementSize);
    out_.surface = fem::meshAroundHole(out_.hole, surfaceOptions);
    if (!out_.surface.quality.valid())
    {
      std::string message = "the surface mesh around the plan is not valid:";
      for (const auto& p : out_.surface.quality.problems)
        message += "\n  " + p;
      throw std::runtime_error(message);
    }
    const fem::SurfaceMesh& surface = out_.surface.mesh;
    auto checkSkin = [&](const ChartPoint& c) {
      if (!chart_.lift(c).allFinite())
        throw std::invalid_argument(
          "the skin map has no surface under the meshed region at " + where(chart_, c) +
          " (a hole in the map or beyond the scan): reduce the region radius or move the plan");
    };
    for (const auto& v : surface.vertices)
      checkSkin(v);
    for (const auto& polygon : surface.polygons)
      for (std::size_t i = 0; i < polygon.size(); ++i)
        checkSkin(0.5 * (surface.vertices[polygon[i]] + surface.vertices[polygon[(i + 1) % polygon.size()]]));
  }

  /// The chart's v bounds: where the scan ends across the plan's width. A CT
  /// often cuts the head (the top slice, the neck), leaving rows at the ends
  /// of the frame with no or only part of the skin; the region stops at the
  /// first fully measured row from each end. Holes further in are not an end
  /// of the scan: meshTheSkin() names them.
  std::pair<double, double> scannedRows() const
  {
    const seg::CylindricalFrame& frame = skin_.frame();
    double extent = 0.0;
    for (const auto& p : out_.hole.points)
      extent = std::max(extent, std::abs(p.x()));
    const double halfWidth = std::min(pi, (extent + options_.regionRadius + options_.elementSize) / chart_.radius());
    const double ic = frame.thetaToIndex(chart_.centreTheta()), di = halfWidth / (2 * pi) * frame.nTheta();
    const int i0 = int(std::floor(ic - di)), i1 = int(std::ceil(ic + di));
    auto rowMeasured = [&](int j) {
      for (int i = i0; i <= i1; ++i)
        if (!std::isfinite(skin_.at(((i % frame.nTheta()) + frame.nTheta()) % frame.nTheta(), j)))
          return false;
      return true;
    };
    const double jc = frame.zToIndex(chart_.centreZ());
    int top = frame.nZ() - 1, bottom = 0;
    while (top > jc && !rowMeasured(top))
      --top;
    while (bottom < jc && !rowMeasured(bottom))
      ++bottom;
    return {frame.indexToZ(bottom) - chart_.centreZ(), frame.indexToZ(top) - chart_.centreZ()};
  }

  /// 3. Skin to bone (§4.5.2), along the ray towards the axis, with the
  /// undermined band and regions, and the excised tissue.
  void meshTheTissue()
  {
    const fem::SurfaceMesh& surface = out_.surface.mesh;
    const seg::RangeMap boneForDepth =
      bone_.empty() ? seg::RangeMap()
                    : boneForTissueDepth(skin_, bone_, options_.noBoneDepth, options_.boneSmoothingPasses);
    const fem::TissueGeometry geometry = skinToBoneGeometry(chart_, skin_, boneForDepth);
    fem::ContinuumMeshOptions continuumOptions = options_.continuumMeshOptions();
    continuumOptions.rim = options_.rim;
    continuumOptions.cutLayers = cutLayersFor(options_, plan_);
    continuumOptions.underminedBase = options_.underminedBase;
    out_.underminingWidth = underminingWidthFor(options_, plan_);
    out_.underminedVertices = fem::underminingBand(surface, out_.sutures, out_.underminingWidth);
    addUnderminedRegions(surface, plan_, chart_, out_.underminedVertices); // and the plan's regions (Undermining.h)
    continuumOptions.underminedVertices = out_.underminedVertices;
    continuumOptions.optimizeInteriorNodes = options_.optimizeInteriorNodes;
    out_.continuum = fem::meshContinuum(surface, out_.sutures, geometry, continuumOptions);
    out_.check.nodeOptimization = out_.continuum.nodeOptimization;
    out_.excisedTissue = fem::meshExcisedTissue(surface, geometry, continuumOptions);
    out_.excisedVolume = fem::meshVolume(out_.excisedTissue.mesh);
    out_.layerCount = options_.layerCount;
    out_.cutLayers = continuumOptions.cutLayers;
    out_.check.mesh = fem::checkMeshQuality(out_.continuum.mesh);
  }

  /// The thesis's counts (§4.5.2), for a cut through every layer (a partial
  /// one shares nodes and adds the hole's floor).
  void checkTheThesisCounts() const
  {
    if (out_.cutLayers != options_.layerCount)
      return;
    const fem::SurfaceMesh& surface = out_.surface.mesh;
    const Eigen::Index nv = Eigen::Index(surface.vertices.size());
    const Eigen::Index ne = Eigen::Index(out_.continuum.edges.size());
    const Eigen::Index nl = options_.layerCount;
    const Eigen::Index np = Eigen::Index(surface.polygons.size());
    if (out_.continuum.mesh.nodeCount() != nl * (2 * nv + ne) + nv + ne ||
        Eigen::Index(out_.continuum.mesh.elements.size()) != nl * np)
      throw std::runtime_error("the continuum mesh does not have N_l(2N_v + N_e) + N_v + N_e nodes and N_l N_p "
                               "elements (§4.5.2): a mesher bug");
  }

  /// 4. The material of every layer (checked: one for each).
  const fem::MaterialTable& layerMaterials()
  {
    out_.materials = options_.layerMaterials();
    for (int layer = 0; layer < options_.layerCount; ++layer)
      if (!out_.materials.count(layer))
        throw std::invalid_argument("simulation options: no material for layer " + std::to_string(layer));
    return out_.materials;
  }

  /// 4'. The skin's pre-tension (SkinPreTension), if any: its stress in the
  /// skin layer, the faces the cut opened in it, and the loads: on the
  /// linear model the traction the cut released; on the large-deformation
  /// one the load that holds the intact face in balance with the stress
  /// everywhere but across the cut (fem/InitialStress.h).
  void preStressTheSkin()
  {
    if (!options_.preTension)
      return;
    SkinPreTension tension = *options_.preTension;
    std::optional<SkinTensionLines> lines;
    std::string why;
    if (tension.followsLines && !tension.lineDirection && tension.alongLines != tension.acrossLines)
    {
      try // the lines of this face, from its landmarks
      {
        const seg::LandmarkPlacement found = seg::placeLandmarks(skin_, bone_);
        lines.emplace(skin_, FaceLayout::fromLandmarks(found.landmarks, skin_));
        tension.lineDirection = [&lines](const SkinPoint& p) { return lines->directionAt(p.theta, p.z); };
      }
      catch (const std::exception& e)
      {
        why = e.what();
      }
    }
    out_.preTension = tension.describe(why);
    initialStress_ = skinPreStress(out_.continuum, out_.surface.mesh, chart_, tension);
    const std::vector<fem::ElementFace> cut = woundFaces(out_.continuum, out_.surface.mesh);
    const Eigen::VectorXd cutTraction = fem::cutFaceTraction(out_.continuum.mesh, initialStress_, cut);
    releasedTraction_ = -cutTraction;
    if (options_.model == TissueModel::LargeDeformation) // the linear model needs only the released traction
      preStressBalance_ =
        fem::initialStressForces(out_.continuum.mesh, initialStress_, assemblyOptions()) - cutTraction;
  }

  fem::AssemblyOptions assemblyOptions() const
  {
    fem::AssemblyOptions assembly;
    assembly.threads = options_.threads;
    return assembly;
  }

  /// 5. The linear model (the preview): assembled, factored, solved once.
  void solveLinear()
  {
    phase(0.2, "Assembly and factorisation (" + std::to_string(out_.continuum.mesh.dofCount()) + " DOF)");
    fem::LinearStaticAnalysis analysis(out_.continuum.mesh, out_.materials, out_.continuum.constraints(),
                                       assemblyOptions());
    factor(analysis);
    phase(0.8, "Solve");
    solve(analysis);
    out_.check.model = TissueModel::LinearElastic;
    out_.check.increments = out_.check.iterations = 1;
  }

  /// 4''. The wound as cut, under the pre-tension, before any suture: the
  /// linear model's gape (the released traction on the open wound).
  void gapeLinear()
  {
    if (!options_.preTension)
      return;
    phase(0.15, "The wound gaping under the skin's tension");
    fem::LinearStaticAnalysis analysis(out_.continuum.mesh, out_.materials, out_.continuum.openWoundConstraints(),
                                       assemblyOptions());
    if (analysis.prepare() != fem::SolverStatus::Success)
    {
      recordTheGape(Eigen::VectorXd::Zero(out_.continuum.mesh.dofCount()),
                    "the open wound cannot be solved: " + analysis.message());
      return;
    }
    recordTheGape(analysis.solve(Eigen::MatrixXd(releasedTraction_)).col(0), {});
  }

  /// 4''. The same in large deformation: the skin's stress ramped up with
  /// its balance on the open wound.
  void gapeInLargeDeformation()
  {
    if (!options_.preTension)
      return;
    phase(0.1, "The wound gaping under the skin's tension");
    fem::NonlinearStaticAnalysis analysis(out_.continuum.mesh, hyperelasticMaterials(),
                                          out_.continuum.openWoundConstraints(), assemblyOptions());
    analysis.setInitialStress(initialStress_);
    const fem::NonlinearResult result = analysis.solve(fem::nodalLoadCase(preStressBalance_), options_.increments,
                                                       options_.newton, progressMonitor(0.1, 0.1, "Gaping"));
    if (result.status == fem::NonlinearStatus::Cancelled)
      throw seg::Cancelled();
    std::string problem;
    if (result.status != fem::NonlinearStatus::Converged)
      problem = result.message + ". The gape shown is not a prediction.";
    recordTheGape(result.displacements, problem);
  }

  /// The area the hole loop's skin nodes enclose under @a u: half the
  /// norm of the loop's vector area (the area projected on the plane it
  /// is largest on), through each border edge's midpoint node.
  double holeLoopArea(const Eigen::VectorXd& u) const
  {
    const fem::Mesh& mesh = out_.continuum.mesh;
    std::vector<Eigen::Vector3d> loop;
    const int n = out_.surface.mesh.holeVertexCount;
    for (int i = 0; i < n; ++i)
    {
      const int vertex = out_.continuum.vertexColumns[std::size_t(i)].front();
      loop.push_back(mesh.nodes.col(vertex) + u.segment<3>(3 * Eigen::Index(vertex)));
      const int edge = out_.continuum.edgeIndex(i, (i + 1) % n);
      if (edge >= 0 && out_.continuum.edgeColumns[std::size_t(edge)].front() >= 0)
      {
        const int middle = out_.continuum.edgeColumns[std::size_t(edge)].front();
        loop.push_back(mesh.nodes.col(middle) + u.segment<3>(3 * Eigen::Index(middle)));
      }
    }
    Eigen::Vector3d area = Eigen::Vector3d::Zero();
    for (std::size_t k = 0; k < loop.size(); ++k)
      area += loop[k].cross(loop[(k + 1) % loop.size()]);
    return 0.5 * area.norm();
  }

  /// Whether the gaping wound is a body and its skin clear of itself, as
  /// the prediction is checked (6', 6''): empty when it is.
  std::string gapeProblem(const Eigen::VectorXd& u) const
  {
    const fem::Mesh& mesh = out_.continuum.mesh;
    const fem::DeformationCheck body = fem::checkDeformation(mesh, u, fem::AssemblyOptions{}.gaussPointsPerDirection);
    const bool linear = options_.model == TissueModel::LinearElastic;
    if (!(body.minDetF > kAdmissibleDetF))
    {
      std::ostringstream text;
      text.precision(3);
      text << (linear ? "the linear gape" : "the gaping") << " turns " << body.invertedElements
           << " elements inside out or crushes them (smallest det F " << body.minDetF << ")"
           << (linear ? ": see the large-deformation prediction" : "");
      return text.str();
    }
    const std::vector<fem::ElementFace> skin = fem::skinFaces(out_.continuum);
    const fem::SurfaceCrossingCheck crossings = fem::checkSurfaceCrossings(mesh, skin, u, 0.05 * options_.elementSize);
    if (crossings.crossingPairs > 0)
      return "the gaping skin passes through itself (" + crossingText(crossings, skin) + ")" +
             (linear ? ": see the large-deformation prediction" : "");
    return {};
  }

  void recordTheGape(const Eigen::VectorXd& u, const std::string& problem)
  {
    WoundGape gape;
    gape.displacements = u;
    gape.problem = problem.empty() ? gapeProblem(u) : problem;
    const fem::Mesh& mesh = out_.continuum.mesh;
    auto at = [&](int node) -> Eigen::Vector3d { return mesh.nodes.col(node) + u.segment<3>(3 * Eigen::Index(node)); };
    std::vector<char> skinNode(std::size_t(mesh.nodeCount()), 0);
    for (const auto& column : out_.continuum.vertexColumns)
      skinNode[std::size_t(column.front())] = 1;
    for (const auto& column : out_.continuum.edgeColumns)
      if (column.front() >= 0)
        skinNode[std::size_t(column.front())] = 1;
    double opening = 0.0;
    int skinSutures = 0;
    for (const fem::Suture& s : out_.continuum.sutures)
    {
      const double cut = (mesh.nodes.col(s.node) - mesh.nodes.col(s.target)).norm();
      const double gaping = (at(s.node) - at(s.target)).norm();
      gape.widestAsCut = std::max(gape.widestAsCut, cut);
      gape.widestGaping = std::max(gape.widestGaping, gaping);
      if (skinNode[std::size_t(s.node)])
      {
        opening += gaping - cut;
        ++skinSutures;
      }
    }
    gape.meanOpening = skinSutures ? opening / skinSutures : 0.0;
    gape.openAreaAsCut = holeLoopArea(Eigen::VectorXd::Zero(u.size()));
    gape.openAreaGaping = holeLoopArea(u);
    for (const auto& column : out_.continuum.vertexColumns)
      gape.skin.push_back(at(column.front()));
    out_.gape = std::move(gape);
  }

  const fem::HyperelasticTable& hyperelasticMaterials()
  {
    for (const auto& [layer, m] : out_.materials)
      out_.hyperelasticMaterials[layer] = fem::HyperelasticMaterial::fromLinear(fem::HyperelasticLaw::NeoHookean, m);
    return out_.hyperelasticMaterials;
  }

  /// Progress of a large-deformation solve between @a from and @a from + @a span.
  fem::NewtonMonitor progressMonitor(double from, double span, const std::string& what) const
  {
    return [this, from, span, what](const fem::NewtonIteration& it) {
      return !options_.progress ||
             options_.progress(from + span * it.loadFraction,
                               what + (it.strictRetry ? " (second try, every increment converged fully)" : "") + ": " +
                                 std::to_string(int(std::lround(100 * it.loadFraction))) + " %, increment " +
                                 std::to_string(it.increment));
    };
  }

  /// 5'. The large-deformation model (the final prediction): neo-Hookean
  /// layers with the small-strain moduli, the sutures' gaps (linear
  /// constraints, exact in large deformation too) closed over increments;
  /// the internal forces at the sutured and fixed nodes are the reactions.
  void solveInLargeDeformation()
  {
    phase(0.2, "Large-deformation closure (" + std::to_string(out_.continuum.mesh.dofCount()) + " DOF)");
    const auto start = std::chrono::steady_clock::now();
    fem::NonlinearStaticAnalysis analysis(out_.continuum.mesh, hyperelasticMaterials(), out_.continuum.constraints(),
                                          assemblyOptions());
    fem::LoadCase load;
    if (options_.preTension)
    {
      analysis.setInitialStress(initialStress_);
      load = fem::nodalLoadCase(preStressBalance_);
    }
    const fem::NonlinearResult result = analysis.solve(load, options_.increments, options_.newton,
                                                       progressMonitor(0.2, 0.65, "Large-deformation closure"));
    if (result.status == fem::NonlinearStatus::Cancelled)
      throw seg::Cancelled();
    out_.displacements = result.displacements;
    out_.times.assemble = result.assembleSeconds;
    out_.times.factor = result.factorSeconds;
    out_.times.solve = std::max(0.0, secondsSince(start) - result.assembleSeconds - result.factorSeconds);
    out_.dofCount = out_.continuum.mesh.dofCount();
    out_.reducedDofCount = fem::resolveConstraints(out_.continuum.mesh, out_.continuum.constraints()).reducedCount();
    // The reactions: what the sutures and supports add to the loads.
    out_.nodalForces = analysis.internalForces(out_.displacements);
    if (options_.preTension)
      out_.nodalForces -= preStressBalance_;
    recordTheSolve(result);
  }

  void recordTheSolve(const fem::NonlinearResult& result)
  {
    PredictionCheck& check = out_.check;
    check.model = TissueModel::LargeDeformation;
    check.converged = result.status == fem::NonlinearStatus::Converged;
    check.closureFraction = result.loadFraction;
    check.increments = int(std::count_if(result.increments.begin(), result.increments.end(),
                                         [](const fem::IncrementRecord& r) { return r.accepted; }));
    check.iterations = int(result.iterations.size());
    check.dampedIncrements = result.stabilizedIncrements;
    check.dissipatedFraction = result.dissipatedFraction;
    check.loosePathStoppedAt = result.loosePathStoppedAt;
    if (!check.converged) // the solver's message says where it stopped, why, and what to try
      check.problem = result.message + ". What is shown is not a prediction.";
  }

  /// 6'. Whether the deformation is a body (thesis §5.5: validating the
  /// results), for either model: det F and the stretches at every point.
  void checkTheDeformation()
  {
    PredictionCheck& check = out_.check;
    // At the points the solver integrates at, so both models are checked
    // alike, and at those the stresses are recovered at (2 x 2 x 2): a
    // 20-node hexahedron can fold over between the solve's 3 x 3 x 3 points
    // (det F -0.63 there, 0.43 at the solve's, on the demo's Z-plasty held
    // to the bone), and a stress read there is no tissue's.
    check.deformation =
      fem::checkDeformation(out_.continuum.mesh, out_.displacements, fem::AssemblyOptions{}.gaussPointsPerDirection);
    const fem::DeformationCheck atStressPoints =
      fem::checkDeformation(out_.continuum.mesh, out_.displacements, fem::kStressRecoveryPointsPerDirection);
    if (atStressPoints.minDetF < check.deformation.minDetF)
    {
      check.deformation.minDetF = atStressPoints.minDetF;
      check.deformation.minDetFElement = atStressPoints.minDetFElement;
    }
    check.deformation.invertedElements = std::max(check.deformation.invertedElements, atStressPoints.invertedElements);
    if (!check.problem.empty())
      return;
    if (check.deformation.minDetF > kAdmissibleDetF)
    {
      checkTheSurfaceCrossings();
      return;
    }
    const int layer = layerOf(check.deformation.minDetFElement);
    std::ostringstream text;
    text << check.deformation.invertedElements << " of " << out_.continuum.mesh.elements.size()
         << " elements are turned inside out or crushed (smallest det F " << check.deformation.minDetF
         << (layer >= 0 ? ", in tissue layer " + std::to_string(layer + 1) + " from the skin" : std::string()) << ")";
    text << (check.model == TissueModel::LinearElastic
               ? ": the linear preview moves the tissue too far to be a body; the large-deformation prediction is "
                 "the one to trust. Undermining the flaps also helps"
               : ": try undermining the flaps and a margin around them, or a finer element size");
    check.problem = text.str();
  }

  /// 6''. Whether the body, each element of which is a body, passes through
  ///      itself: the skin (a failure), then the whole boundary (a caveat),
  ///      the sutured sides welded where they meet. Crossings shallower than
  ///      a twentieth of the element size are surfaces lying on each other
  ///      (the undermined plane, where the sampled faces' chords cross).
  void checkTheSurfaceCrossings()
  {
    PredictionCheck& check = out_.check;
    const fem::Mesh& mesh = out_.continuum.mesh;
    const double tolerance = 0.05 * options_.elementSize;
    const std::vector<fem::ElementFace> skin = fem::skinFaces(out_.continuum);
    check.skinCrossings = fem::checkSurfaceCrossings(mesh, skin, out_.displacements, tolerance);
    std::vector<int> all(std::size_t(mesh.nodeCount()));
    std::iota(all.begin(), all.end(), 0);
    const std::vector<fem::ElementFace> boundary = fem::boundaryFacesOnNodes(mesh, all);
    check.tissueCrossings = fem::checkSurfaceCrossings(mesh, boundary, out_.displacements, tolerance);
    if (check.skinCrossings.crossingPairs > 0)
    {
      check.problem = "the skin passes through itself (" + crossingText(check.skinCrossings, skin) + ")" +
                      (check.model == TissueModel::LinearElastic
                         ? ": the linear preview moves the tissue too far to be a body; the large-deformation "
                           "prediction is the one to trust"
                         : ": the model has no contact between parts of the skin, so a flap folded into its "
                           "neighbour is not what the skin does; try undermining the flaps and a margin around "
                           "them, a longer cut (less transposition), or a finer element size");
      return;
    }
    if (check.tissueCrossings.crossingPairs > 0)
      addCaveat("the deep tissue passes through itself (" + crossingText(check.tissueCrossings, boundary) +
                "): the model has no contact between the wound's walls or between a flap and the tissue "
                "under it, so there the tissue is squeezed through itself where it would bunch up; the skin "
                "does not pass through itself and its shape is shown, but the stresses in the deep tissue "
                "near that point are not to be read");
  }

  /// 6'''. Elements the mesher could not shape within the limits
  ///       (fem::ElementQualityLimits) even after moving the interior nodes,
  ///       as a caveat that says where the worst are: their strains and
  ///       stresses are less accurate than the rest's. (An element inverted
  ///       at an integration point is refused by the solver itself.)
  void stateTheMeshQuality()
  {
    const fem::MeshQualityCheck& q = out_.check.mesh;
    if (q.elements == 0 || q.withinLimits())
      return;
    const fem::ElementQualityLimits limits;
    std::ostringstream text;
    text.precision(3);
    text << q.poorElements << " of " << q.elements << " elements are shaped outside the limits a large-motion mesh "
         << "should keep (";
    if (q.poorJacobian > 0)
      text << q.poorJacobian << " with a scaled Jacobian under " << limits.minScaledJacobian << ", the worst "
           << q.minScaledJacobian << (q.minScaledJacobian <= 0.0 ? " (inside out at a node)" : "") << " "
           << whereInTheTissue(q.worstJacobianElement, q.worstJacobianAt);
    if (q.poorJacobian > 0 && q.poorEdgeRatio > 0)
      text << "; ";
    if (q.poorEdgeRatio > 0)
      text << q.poorEdgeRatio << " longer than " << limits.maxEdgeRatio << " times their shortest edge, the worst "
           << q.maxEdgeRatio << " times " << whereInTheTissue(q.worstEdgeRatioElement, q.worstEdgeRatioAt);
    text << ")";
    if (out_.check.nodeOptimization.movedNodes > 0)
      text << " after " << out_.check.nodeOptimization.movedNodes << " interior nodes were moved to improve them";
    text << ": the strains and stresses in those elements are less accurate than elsewhere (the tissue between skin "
            "and bone is thin or steep there for the element size)";
    addCaveat(text.str());
  }

  /// "in tissue layer 3 from the skin at x, y, z mm, 23 mm from the wound".
  std::string whereInTheTissue(int element, const Eigen::Vector3d& at) const
  {
    std::ostringstream text;
    text.precision(3);
    const int layer = layerOf(element);
    text << (layer >= 0 ? "in tissue layer " + std::to_string(layer + 1) + " from the skin" : "in the tissue") << " at "
         << at.x() << ", " << at.y() << ", " << at.z() << " mm";
    double nearest = std::numeric_limits<double>::infinity();
    for (const fem::Suture& s : out_.continuum.sutures)
      nearest = std::min(nearest, (out_.continuum.mesh.nodes.col(s.node) - at).norm());
    if (std::isfinite(nearest))
      text << ", " << std::lround(nearest) << " mm from the wound";
    return text.str();
  }

  /// Caveats add up: "...; and ...".
  void addCaveat(const std::string& caveat)
  {
    std::string& all = out_.check.caveat;
    all += (all.empty() ? "" : "; and ") + caveat;
  }

  /// "12 pairs of surface triangles cross, the deepest by 2.67 mm, in tissue
  /// layer 2 from the skin and in tissue layer 2 from the skin at x, y, z mm".
  std::string crossingText(const fem::SurfaceCrossingCheck& c, const std::vector<fem::ElementFace>& faces) const
  {
    std::ostringstream text;
    text.precision(3);
    text << c.crossingPairs << " pairs of surface triangles cross, the deepest by " << c.deepest << " mm, "
         << whereOnTheBody(faces[std::size_t(c.faceA)]) << " and " << whereOnTheBody(faces[std::size_t(c.faceB)])
         << " at " << c.where.x() << ", " << c.where.y() << ", " << c.where.z() << " mm";
    return text.str();
  }

  /// The tissue layer (0 the skin) of element @a e, or -1.
  int layerOf(int e) const
  {
    const std::vector<int>& layers = out_.continuum.elementLayer;
    return e >= 0 && std::size_t(e) < layers.size() ? layers[std::size_t(e)] : -1;
  }

  /// "on the skin" or "in tissue layer 2 from the skin", for a boundary face.
  std::string whereOnTheBody(const fem::ElementFace& face) const
  {
    const int layer = layerOf(face.element);
    if (layer == 0 && face.face == 2) // the top face of the skin layer (fem::skinFaces)
      return "on the skin";
    return layer >= 0 ? "in tissue layer " + std::to_string(layer + 1) + " from the skin" : "in the tissue";
  }

  /// The linear model with its constraints, assembled and factored.
  void factor(fem::LinearStaticAnalysis& analysis)
  {
    const auto prepareStart = std::chrono::steady_clock::now();
    const fem::SolverStatus status = analysis.prepare();
    prepareWall_ = secondsSince(prepareStart);
    if (status != fem::SolverStatus::Success)
      throw std::runtime_error("the model of the plan cannot be solved: " + analysis.message());
  }

  /// The displacements and the nodal forces K U.
  void solve(fem::LinearStaticAnalysis& analysis)
  {
    out_.displacements = options_.preTension
                           ? Eigen::VectorXd(analysis.solve(Eigen::MatrixXd(releasedTraction_)).col(0))
                           : analysis.solve(fem::LoadCase{});
    out_.times.assemble = analysis.times().assemble + analysis.times().constrain;
    out_.times.factor = std::max(0.0, prepareWall_ - out_.times.assemble);
    out_.times.solve = analysis.times().solve;
    out_.dofCount = out_.continuum.mesh.dofCount();
    out_.reducedDofCount = analysis.constraintMap().reducedCount();
    if (!out_.displacements.allFinite())
      throw std::runtime_error("the solve of the plan gave non-finite displacements");
    out_.nodalForces = analysis.internalForces(out_.displacements); // K U less the loads: the reactions
    if (options_.preTension)
      out_.nodalForces -= releasedTraction_;
  }

  /// 7. Closure forces: no load acts on the model, so K U at a sutured node
  /// is what its suture pulls with, and at a fixed node what the bone holds;
  /// summed per sutured pair of the plan.
  void closureForces()
  {
    ClosureForces& closure = out_.closure;
    for (const fem::Suture& s : out_.continuum.sutures)
    {
      const Eigen::Vector3d f = out_.nodalForces.segment<3>(3 * Eigen::Index(s.node));
      closure.sutures.push_back({s.node, s.target, f});
      closure.magnitudeSum += f.norm();
      closure.largest = std::max(closure.largest, f.norm());
    }
    for (int node : out_.continuum.fixedNodes)
      closure.supportReaction += out_.nodalForces.segment<3>(3 * Eigen::Index(node));
    // The deep plane pushes back along its normal on each sliding node: the
    // node's own K U less what the sutures sewn onto it pull with.
    std::map<int, Eigen::Vector3d> sewnOnto;
    for (const SutureForce& s : closure.sutures)
      sewnOnto.try_emplace(s.target, Eigen::Vector3d::Zero()).first->second += s.force;
    for (const fem::SlidingNode& sliding : out_.continuum.slidingNodes)
    {
      Eigen::Vector3d onThePlane = out_.nodalForces.segment<3>(3 * Eigen::Index(sliding.node));
      if (const auto it = sewnOnto.find(sliding.node); it != sewnOnto.end())
        onThePlane += it->second;
      closure.supportReaction += onThePlane;
    }
    // The refined sub-pairs of each plan pair follow one another in
    // out_.sutures (refineHole()), as many as its segment's pieces.
    const int n = plan_.pointCount();
    std::size_t first = 0;
    for (const fem::SutureEdgePair& pair : plan_.sutures())
    {
      const int pieces = refined_.piecesPerSegment[segmentOfEdge(pair.a[0], pair.a[1], n)];
      closure.edges.push_back(forceAlong(pair, first, pieces));
      first += std::size_t(pieces);
    }
  }

  /// The suture forces at the nodes along the refined sub-pairs
  /// [first, first + pieces) of the plan's pair @a pair.
  SuturedEdgeForce forceAlong(const fem::SutureEdgePair& pair, std::size_t first, int pieces) const
  {
    std::vector<char> alongPair(std::size_t(out_.continuum.mesh.nodeCount()), 0);
    for (std::size_t k = first; k < first + std::size_t(pieces) && k < out_.sutures.size(); ++k)
      for (const auto& e : {out_.sutures[k].a, out_.sutures[k].b})
      {
        for (int v : e)
          for (int node : out_.continuum.vertexColumns[v])
            alongPair[node] = 1;
        const int edge = out_.continuum.edgeIndex(e[0], e[1]);
        if (edge >= 0)
          for (int node : out_.continuum.edgeColumns[edge])
            alongPair[node] = 1;
      }
    SuturedEdgeForce edgeForce;
    edgeForce.edges = pair;
    for (const SutureForce& f : out_.closure.sutures)
      if (alongPair[f.node])
      {
        ++edgeForce.sutureCount;
        edgeForce.resultant += f.force;
        edgeForce.magnitudeSum += f.force.norm();
      }
    edgeForce.resultantMagnitude = edgeForce.resultant.norm();
    return edgeForce;
  }

  /// 8. What the display and the report need: the suture gaps and the skin
  /// before and after.
  void skinForTheDisplay()
  {
    for (const auto& s : out_.continuum.sutures)
    {
      const auto& x = out_.continuum.mesh.nodes;
      out_.maxSutureGapBefore = std::max(out_.maxSutureGapBefore, (x.col(s.node) - x.col(s.target)).norm());
      out_.maxSutureGap =
        std::max(out_.maxSutureGap, (out_.displacedNode(s.node) - out_.displacedNode(s.target)).norm());
    }
    const fem::SurfaceMesh& surface = out_.surface.mesh;
    DisplacedSkin& top = out_.skin;
    top.chart = surface.vertices;
    top.polygons = surface.polygons;
    top.holeVertexCount = surface.holeVertexCount;
    for (std::size_t v = 0; v < surface.vertices.size(); ++v)
    {
      const int node = out_.continuum.vertexColumns[v].front();
      top.nodes.push_back(node);
      top.original.push_back(out_.continuum.mesh.nodes.col(node));
      top.displaced.push_back(out_.displacedNode(node));
    }
  }

  /// 9. Z-plasty (§2.1, Fig. 2.2). Each end of the central limb has two
  /// copies on the border: one is a flap tip, carried by the sutures to a
  /// limb tip, where it ends on the new central limb across the axis; the
  /// other is the corner the other flap pivots about (a shared vertex of a
  /// suture pair, corner rule) and stays in the surrounding skin. The
  /// lengthening along the old central axis is the change of distance
  /// between those pivot copies (ideally from the short diagonal to the long
  /// one of the Z's parallelogram, zPlastyGeometricGain()); that is what is
  /// measured here.
  void zPlastyGain()
  {
    if (plan_.generator() != "z" && plan_.generator() != "multiple-z")
      return;
    const DisplacedSkin& top = out_.skin;
    const std::array<int, 2> tips = zPlastyFlapTips(plan_);
    const int n = plan_.pointCount();
    std::vector<bool> corner(holeLoopSize(n), false);
    for (const auto& s : plan_.sutures())
    {
      if (s.a[0] == s.b[0])
        corner[s.a[0]] = true;
      if (s.a[1] == s.b[1])
        corner[s.a[1]] = true;
    }
    std::array<Eigen::Vector3d, 2> before, after;
    for (int t = 0; t < 2; ++t)
    {
      const int left = tips[t], right = rightSideVertex(tips[t], n);
      const int l = out_.refinedVertexOf[left], r = out_.refinedVertexOf[right];
      int v = (top.displaced[l] - top.original[l]).norm() <= (top.displaced[r] - top.original[r]).norm() ? l : r;
      if (corner[left] != corner[right])
        v = corner[left] ? l : r;
      before[t] = top.original[v];
      after[t] = top.displaced[v];
    }
    ZPlastyPrediction z;
    z.predicted = zPlastyPredictedGain(before, after, centralAxis(plan_, skin_));
    const auto angle = plan_.parameters().find("limb_angle");
    if (angle != plan_.parameters().end())
    {
      z.limbAngle = angle->second;
      z.geometric = zPlastyGeometricGain(z.limbAngle);
      if (z.limbAngle >= 30.0 * pi / 180.0 - 1e-12 && z.limbAngle <= 90.0 * pi / 180.0 + 1e-12)
        z.theoretical = zPlastyTheoreticalGain(std::clamp(z.limbAngle, 30.0 * pi / 180.0, 90.0 * pi / 180.0));
    }
    out_.zPlasty = z;
  }

  const seg::RangeMap& skin_;
  const seg::RangeMap& bone_;
  const IncisionPlan& plan_;
  const SimulationOptions& options_;
  const SkinChart chart_;
  RefinedHole refined_;
  double prepareWall_ = 0.0;
  fem::InitialStress initialStress_; ///< the skin's pre-stress (preStressTheSkin())
  Eigen::VectorXd releasedTraction_; ///< the traction the cut released (3N)
  Eigen::VectorXd preStressBalance_; ///< what holds the intact face in balance (3N)
  PlanPrediction out_;
};

} // namespace

const char* tissueModelId(TissueModel model)
{
  return model == TissueModel::LargeDeformation ? "large-deformation" : "linear";
}

std::string tissueModelDescription(TissueModel model)
{
  return model == TissueModel::LargeDeformation
           ? "large deformation: compressible neo-Hookean layers (same small-strain moduli), sutures closed over "
             "load increments"
           : "linear elastic, small strain (the preview)";
}

std::optional<TissueModel> tissueModelFromId(const std::string& id)
{
  if (id == "linear")
    return TissueModel::LinearElastic;
  if (id == "large-deformation")
    return TissueModel::LargeDeformation;
  return std::nullopt;
}

double underminingWidthFor(const SimulationOptions& options, const IncisionPlan& plan)
{
  return options.underminingWidth.value_or(plan.underminingBand());
}

int cutLayersFor(const SimulationOptions& options, const IncisionPlan& plan)
{
  if (options.cutLayers)
    return *options.cutLayers == 0 ? options.layerCount : *options.cutLayers;
  return layersCutTo(plan.cutDepth(), options.layerCount);
}

std::string checkSummary(const PredictionCheck& c)
{
  std::ostringstream text;
  text.precision(3);
  text << "smallest det F " << c.deformation.minDetF << ", largest stretch " << c.deformation.maxStretch << ", "
       << c.deformation.invertedElements << " inverted elements, ";
  if (c.skinCrossings.triangles == 0)
    text << "not checked for passing through itself";
  else if (c.skinCrossings.crossingPairs > 0)
    text << "the skin PASSES THROUGH ITSELF (" << c.skinCrossings.crossingPairs << " crossing triangle pairs)";
  else
  {
    text << "the skin does not pass through itself";
    if (c.tissueCrossings.crossingPairs > 0)
      text << ", the deep tissue does (by up to " << c.tissueCrossings.deepest << " mm)";
    else
      text << ", nor does the deep tissue";
  }
  if (c.model == TissueModel::LargeDeformation)
  {
    text << ", " << c.increments << " increments (" << c.iterations << " Newton iterations), ";
    if (c.dampedIncrements > 0)
      text << c.dampedIncrements << " of them damped through an instability (" << 100.0 * c.dissipatedFraction
           << " % of the strain energy dissipated), ";
    if (c.loosePathStoppedAt >= 0.0)
      text << "solved a second time with every increment converged fully after the faster path stopped at "
           << std::lround(100.0 * c.loosePathStoppedAt) << " % of the closure, ";
    text << (c.converged ? "converged at full closure" : "NOT converged");
  }
  if (c.mesh.elements > 0)
  {
    text << "; mesh of " << c.mesh.elements << " elements: smallest scaled Jacobian " << c.mesh.minScaledJacobian
         << ", largest edge ratio " << c.mesh.maxEdgeRatio << ", " << c.mesh.poorJacobian << " below 0.2";
    if (c.nodeOptimization.movedNodes > 0)
      text << " (" << c.nodeOptimization.poorElementsBefore << " before " << c.nodeOptimization.movedNodes
           << " interior nodes were moved)";
  }
  return text.str();
}

std::string checkWarning(const PredictionCheck& c)
{
  if (c.problem.empty() && c.admissible())
    return {};
  const std::string problem = c.problem.empty() ? checkSummary(c) : c.problem;
  return (c.model == TissueModel::LinearElastic ? "WARNING (linear preview): " : "NOT A PREDICTION: ") + problem;
}

std::string materialProblem(double youngsModulusMPa, double poissonRatio)
{
  if (!std::isfinite(youngsModulusMPa) || !(youngsModulusMPa > 0.0))
    return "Young's modulus E must be a positive number (tissue has some stiffness)";
  if (!std::isfinite(poissonRatio) || !(poissonRatio > 0.0) || !(poissonRatio < 0.5))
    return "Poisson's ratio \u03bd must lie strictly between 0 and 0.5 (0.5 is incompressible, which this "
           "displacement model cannot solve; tissue is usually 0.45\u20130.49)";
  return {};
}

SkinDifference skinDifference(const PlanPrediction& a, const PlanPrediction& b)
{
  if (a.skin.original.size() != b.skin.original.size() || a.skin.displaced.size() != a.skin.original.size() ||
      b.skin.displaced.size() != b.skin.original.size())
    throw std::invalid_argument("the two predictions are not on one mesh: solve the same plan with the same element "
                                "size, region and layers to compare them");
  SkinDifference d;
  for (std::size_t v = 0; v < a.skin.displaced.size(); ++v)
  {
    if ((a.skin.original[v] - b.skin.original[v]).norm() > 1e-9)
      throw std::invalid_argument("the two predictions are not on one mesh: their skin vertices differ");
    const double apart = (a.skin.displaced[v] - b.skin.displaced[v]).norm();
    d.largest = std::max(d.largest, apart);
    d.mean += apart;
  }
  if (!a.skin.displaced.empty())
    d.mean /= double(a.skin.displaced.size());
  return d;
}

PlanPrediction simulatePlan(const seg::RangeMap& skin, const seg::RangeMap& bone, const IncisionPlan& plan,
                            const SimulationOptions& options)
{
  return PlanModel(skin, bone, plan, options).run(false);
}

PlanPrediction meshPlan(const seg::RangeMap& skin, const seg::RangeMap& bone, const IncisionPlan& plan,
                        const SimulationOptions& options)
{
  return PlanModel(skin, bone, plan, options).run(true);
}

} // namespace caps::planning
