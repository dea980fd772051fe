// `caps plan`: a procedure placed on a patient's skin and simulated end to
// end: CT → skin and bone range maps → plan → measurements
// on the skin → mesh skin to bone → sutures closed → predicted skin.

#include "modules/incision/PlanCommands.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <numbers>
#include <regex>
#include <sstream>

#include <vtkCellArray.h>
#include <vtkDoubleArray.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include "fem/ElementGeometry.h"
#include "fem/ElementQuality.h"
#include "fem/FiniteStrainStress.h"
#include "planning/CutOnSoundSkin.h"
#include "fem/NodalStress.h"
#include "fem/VtuWriter.h"
#include "modules/incision/IncisionLogic.h"
#include "planning/PlanDisplay.h"
#include "planning/PlanRecipe.h"
#include "planning/PlanSimulation.h"
#include "planning/UnderminingStudy.h"
#include "planning/ConvergenceStudy.h"
#include "render/XyPlot.h"
#include "planning/WoundStress.h"
#include "planning/WoundTension.h"
#include "modules/rangemap/RangeMapLogic.h"
#include "modules/volumes/CommandLine.h"
#include "scene/RangeMapNode.h"
#include "scene/Scene.h"
#include "scene/VolumeNode.h"
#include "segmentation/SkinShade.h"

namespace fs = std::filesystem;

namespace caps {
namespace {

constexpr double kDegree = std::numbers::pi / 180.0;
/// The skin's pre-tension of a new plan (N/mm along and across the tension
/// lines): SkinPreTension's own, from the literature it cites.
const std::array<double, 2> kDefaultPreTension{planning::SkinPreTension{}.alongLines,
                                               planning::SkinPreTension{}.acrossLines};

const char* kPlanUsage =
  "usage: caps plan CT --procedure ID --at THETA,Z --out DIR [--param NAME=VALUE ...]\n"
  "                 [--move I=THETA,Z ...] [--offset V=DU,DV ...] [--element-size MM] [--series N|UID]\n"
  "       caps plan CT --replay PLAN.json --out DIR [--other-ct] [--move ...] [--offset ...] [...]\n"
  "\n"
  "Places a procedure on the patient's skin and predicts the result (thesis §4.4-4.6):\n"
  "segments the CT, unwraps skin and bone into range maps, places the procedure's cut\n"
  "centred at THETA (degrees around the head axis, -90 = the front of the face) and Z\n"
  "(mm along the axis, as `caps rangemap` prints them), measures it on the skin, meshes\n"
  "the skin down to the bone, closes the sutures and writes into DIR:\n"
  "  measurements.csv     limb lengths and angles on the skin, excised area and volume,\n"
  "                       closure force, peak skin stress within 10 mm of the wound,\n"
  "                       Z-plasty gain\n"
  "  skin-before.vtp      the skin around the wound before the operation: element faces\n"
  "                       subdivided 4 x 4 with the CT's skin detail (§4.7), shaded by the\n"
  "                       tissue under the skin; displacement (mm), von Mises and mean\n"
  "                       stress (kPa), strain and body coordinates as point data\n"
  "  skin-after.vtp       the same surface after it\n"
  "  model.vtu            the finite element model of the prediction with its displacements\n"
  "                       and nodal stresses (Cauchy, det F and stretch in large deformation)\n"
  "  plan.json            the plan as the operations that made it, with the CT's SHA-256\n"
  "                       and the CAPS version: --replay makes the same plan and prediction\n"
  "\n"
  "  --procedure ID       one of data/procedures/ (e.g. z-plasty, elliptical-excision)\n"
  "  --param NAME=VALUE   a parameter of the procedure in its file's units (mm, degrees,\n"
  "                       ratio); the others take their defaults\n"
  "  --move I=THETA,Z     moves cut point I (from 0, in the scalpel's order) to THETA degrees,\n"
  "                       Z mm; repeatable, applied in the order given after the placement\n"
  "  --offset V=DU,DV     moves border point V of the hole away from its twin by DU, DV mm\n"
  "                       (around the head, along the axis) to make an excision; repeatable\n"
  "  --undermine-region \"THETA,Z;THETA,Z;...\"\n"
  "                       undermines the skin inside the closed polygon of these points\n"
  "                       (degrees, mm; at least 3, the last joined to the first), besides\n"
  "                       the band; repeatable, the regions add up; kept in plan.json,\n"
  "                       tinted blue and hatched in skin_colour of the VTP\n"
  "  --undermining MM     the band undermined along the sutured edges (§3.2.4), 0 for none;\n"
  "                       default the procedure's own (its file's `undermining`, e.g. the\n"
  "                       Z-plasty's flaps and a margin), or the replayed plan's. Undermined\n"
  "                       tissue slides on the deep plane: u.n = 0 there, free along it\n"
  "  --replay PLAN.json   instead of --procedure/--at/--param: rebuilds the plan of a plan.json\n"
  "                       from its operations; refused when it was made on another CT\n"
  "  --other-ct           replays a plan made on another CT (another scan or patient) anyway\n"
  "  --element-size MM    element size at the wound (default 2, or the replayed plan's)\n"
  "  --stitch-spacing MM  the spacing of the skin stitches the tension per stitch is given\n"
  "                       for (default 4; the tension per cm does not depend on it)\n"
  "  --cut-depth N        the cut goes through the top N of the model's 3 tissue layers\n"
  "                       (1: the skin, 2: skin and fat, 3: down to the bone); default the\n"
  "                       procedure's depth (its file's `depth`: the shipped ones cut skin\n"
  "                       and fat and raise their flaps on the fascia), or the replayed\n"
  "                       plan's; below it the tissue stays whole, only the layers cut are\n"
  "                       sutured, and undermined tissue slides on the plane at its root\n"
  "  --undermine W,W,...  also closes the plan with the skin undermined W mm around the\n"
  "                       sutured edges (§3.2.4: freed from the bone), for each width, and\n"
  "                       writes undermining.csv: closure force and peak skin stress near\n"
  "                       the wound against undermining width, plotted in undermining.png\n"
  "  --study convergence  also solves the plan with the mesh refined (element sizes 1.5 h,\n"
  "                       h, h/1.5), with 2, 3 and 4 tissue layers, and with the meshed\n"
  "                       region 15, 25 and 35 mm wide, rim free and clamped, and writes\n"
  "                       convergence.csv: tension per cm, mean and peak wound stress,\n"
  "                       gain, largest displacement and the change from level to level\n"
  "  --pre-tension ALONG,ACROSS|none\n"
  "                       the tension the living skin carries before the cut, in N/m along\n"
  "                       and across the relaxed skin tension lines (default 10,5: in-vivo\n"
  "                       skin tension, Flynn et al. 2011; directions from the facial\n"
  "                       landmarks, the mean in every direction without them), or none (the\n"
  "                       thesis's slack skin); default the replayed plan's. The wound gapes\n"
  "                       under it before it is sutured, and the sutures close it against it\n"
  "  --series N|UID       in a folder with several series, the one to use\n"
  "  --model linear|large-deformation\n"
  "                       the model of the tissue (default large-deformation, or the\n"
  "                       replayed plan's): compressible neo-Hookean layers in large\n"
  "                       deformation with the sutures closed over load increments (the\n"
  "                       prediction), or linear elastic, small strain (the instant preview)\n"
  "\n"
  "The tissue has assumed moduli (skin 0.15, fat 0.01, muscle 0.05 MPa, Poisson 0.45),\n"
  "the bone fixed: a first prediction, not a measurement. Every prediction is checked:\n"
  "the smallest det F over all integration points (is the deformed mesh still a body?),\n"
  "the largest stretch, the increments and whether the solve reached the full closure;\n"
  "measurements.csv and plan.json (\"prediction\") record them.\n"
  "Exit status: 0 when written, 1 when the CT or the plan cannot be used (the message\n"
  "says why), 2 on wrong usage, 3 when the files are written but the large-deformation\n"
  "solve did not reach the full closure or its result is not a body (the files hold the\n"
  "last converged state, marked as such: not a prediction).\n";

/// A --move or --offset, in the order given.
struct PlanEdit
{
  bool move = true; ///< else an offset
  int index = 0;    ///< cut point or border point
  double a = 0.0;   ///< degrees (move) or mm around the head (offset)
  double b = 0.0;   ///< mm along the axis
};

struct PlanArgs : cli::CtCommandArgs
{
  std::string procedure;
  std::optional<std::pair<double, double>> at; ///< degrees, mm
  std::map<std::string, double> params;        ///< file units
  std::vector<PlanEdit> edits;
  std::vector<std::vector<std::pair<double, double>>> undermineRegions; ///< degrees, mm
  std::optional<fs::path> replay;
  bool otherCt = false;
  std::optional<double> elementSize;          ///< mm; default 2, or the replayed plan's
  std::optional<int> cutLayers;               ///< --cut-depth; default the procedure's, or the replayed plan's
  std::vector<double> undermineWidths;        ///< mm, the --undermine study; empty: none
  std::optional<planning::TissueModel> model; ///< --model; default large deformation, or the replayed plan's
  std::optional<double> underminingWidth;     ///< --undermining mm; default the procedure's, or the replayed plan's
  double stitchSpacing = planning::kDefaultStitchSpacing; ///< mm, --stitch-spacing
  bool convergenceStudy = false;                          ///< --study convergence
  /// --pre-tension: N/mm along and across the lines, or none (nullopt inside);
  /// unset: the default, or the replayed plan's.
  std::optional<std::optional<std::array<double, 2>>> preTension;
};

/// "ALONG,ACROSS" in N/m (each 0 to 200) or "none"; to N/mm.
bool parsePreTension(const std::string& text, std::optional<std::array<double, 2>>& tension)
{
  if (text == "none")
  {
    tension.reset();
    return true;
  }
  const std::size_t comma = text.find(',');
  double along = 0.0, across = 0.0;
  if (comma == std::string::npos || !cli::parseNumber(text.substr(0, comma), along) ||
      !cli::parseNumber(text.substr(comma + 1), across) || !(along >= 0.0 && along <= 200.0) ||
      !(across >= 0.0 && across <= 200.0))
    return false;
  tension = std::array<double, 2>{along / 1000.0, across / 1000.0};
  return true;
}

/// model.vtu's point data: the prediction's displacements and the stress of
/// the model that made it at the nodes (averaged within each tissue layer):
/// Cauchy stress, det F and the largest stretch for a large-deformation
/// prediction, the small-strain stress for the linear preview.
std::vector<fem::VtuArray> modelArrays(const planning::PlanPrediction& p)
{
  const Eigen::Map<const Eigen::Matrix3Xd> u(p.displacements.data(), 3, p.displacements.size() / 3);
  std::vector<fem::VtuArray> arrays{{"displacement_mm", Eigen::MatrixXd(u)}};
  if (p.check.model == planning::TissueModel::LargeDeformation && !p.hyperelasticMaterials.empty())
  {
    const fem::FiniteStrainNodalField f =
      fem::recoverFiniteStrainNodalField(p.continuum.mesh, p.hyperelasticMaterials, p.displacements);
    arrays.push_back({"cauchy_stress_MPa", f.cauchy});
    arrays.push_back({"det_F", f.detF.transpose()});
    arrays.push_back({"largest_stretch", f.maxStretch().transpose()});
  }
  else
    arrays.push_back({"stress_MPa", fem::recoverNodalStresses(p.continuum.mesh, p.materials, p.displacements).stress});
  return arrays;
}

/// model.vtu's cell data: the tissue layer (1 = the skin) of each element
/// and its shape quality in the reference state (fem::elementQuality: the
/// smallest scaled Jacobian and the edge ratio), so the elements the check
/// counts as poor can be found with any VTK reader.
std::vector<fem::VtuArray> elementArrays(const planning::PlanPrediction& p)
{
  const fem::Mesh& mesh = p.continuum.mesh;
  const Eigen::Index n = Eigen::Index(mesh.elements.size());
  Eigen::MatrixXd layer(1, n), jacobian(1, n), edgeRatio(1, n);
  for (Eigen::Index e = 0; e < n; ++e)
  {
    layer(0, e) = std::size_t(e) < p.continuum.elementLayer.size() ? p.continuum.elementLayer[std::size_t(e)] + 1 : 0;
    const fem::ElementQuality q = fem::elementQuality(mesh, int(e));
    jacobian(0, e) = q.scaledJacobian;
    edgeRatio(0, e) = q.edgeRatio;
  }
  return {{"tissue_layer", layer}, {"scaled_jacobian", jacobian}, {"edge_ratio", edgeRatio}};
}

/// "W,W,..." of undermining widths in mm, each in [0, 100].
bool parseWidths(const std::string& text, std::vector<double>& widths)
{
  widths.clear();
  std::size_t start = 0;
  while (start <= text.size())
  {
    const std::size_t comma = std::min(text.find(',', start), text.size());
    double w = 0.0;
    if (!cli::parseNumber(text.substr(start, comma - start), w) || !(w >= 0.0) || w > 100.0)
      return false;
    widths.push_back(w);
    start = comma + 1;
  }
  return !widths.empty();
}

/// "THETA,Z;THETA,Z;..." (degrees, mm), each finite; at least one point
/// (fewer than 3 are refused with the plan's message).
bool parseRegion(const std::string& text, std::vector<std::pair<double, double>>& points)
{
  points.clear();
  std::size_t start = 0;
  while (start <= text.size())
  {
    const std::size_t semicolon = std::min(text.find(';', start), text.size());
    const std::string point = text.substr(start, semicolon - start);
    const std::size_t comma = point.find(',');
    double theta = 0.0, z = 0.0;
    if (comma == std::string::npos || !cli::parseNumber(point.substr(0, comma), theta) ||
        !cli::parseNumber(point.substr(comma + 1), z) || !std::isfinite(theta) || !std::isfinite(z))
      return false;
    points.emplace_back(theta, z);
    start = semicolon + 1;
  }
  return !points.empty();
}

/// "I=A,B" with I a whole number from 0 and A, B finite.
bool parseEdit(const std::string& text, bool move, PlanEdit& edit)
{
  int index = -1;
  char tail = 0;
  edit.move = move;
  if (std::sscanf(text.c_str(), "%d=%lf,%lf%c", &index, &edit.a, &edit.b, &tail) != 3 || index < 0 ||
      !std::isfinite(edit.a) || !std::isfinite(edit.b))
    return false;
  edit.index = index;
  return true;
}

/// The options of the model and its studies (--element-size ... --undermine).
std::optional<std::string> parseModelOption(const std::string& a, const std::vector<std::string>& args, std::size_t& i,
                                            PlanArgs& parsed)
{
  const bool hasValue = i + 1 < args.size();
  if (a == "--element-size")
  {
    double size = 0.0;
    if (!hasValue || !cli::parseNumber(args[++i], size) || size <= 0.2 || size > 20.0)
      return "--element-size needs a length in mm between 0.2 and 20";
    parsed.elementSize = size;
  }
  else if (a == "--stitch-spacing")
  {
    double spacing = 0.0;
    if (!hasValue || !cli::parseNumber(args[++i], spacing) || spacing < 1.0 || spacing > 20.0)
      return "--stitch-spacing needs the distance between two skin stitches in mm, between 1 and 20";
    parsed.stitchSpacing = spacing;
  }
  else if (a == "--cut-depth")
  {
    double layers = 0.0;
    if (!hasValue || !cli::parseNumber(args[++i], layers) || (layers != 1.0 && layers != 2.0 && layers != 3.0))
      return "--cut-depth needs the number of tissue layers the cut goes through: 1 (skin), 2 (skin and fat) "
             "or 3 (down to the bone)";
    parsed.cutLayers = int(layers);
  }
  else if (a == "--model")
  {
    parsed.model = hasValue ? planning::tissueModelFromId(args[i + 1]) : std::nullopt;
    if (!parsed.model)
      return "--model needs linear (the small-strain preview) or large-deformation (the final prediction)";
    ++i;
  }
  else if (a == "--undermining")
  {
    double width = 0.0;
    if (!hasValue || !cli::parseNumber(args[++i], width) || width < 0.0 || width > 100.0)
      return "--undermining needs the band undermined along the sutured edges in mm, 0 (none) to 100";
    parsed.underminingWidth = width;
  }
  else if (a == "--pre-tension")
  {
    std::optional<std::array<double, 2>> tension;
    if (!hasValue || !parsePreTension(args[++i], tension))
      return "--pre-tension needs ALONG,ACROSS in N/m (0 to 200 each; e.g. 10,5) along and across the skin "
             "tension lines, or none";
    parsed.preTension = tension;
  }
  else if (a == "--study")
  {
    if (!hasValue || args[++i] != "convergence")
      return "--study needs convergence (the plan solved again with the mesh refined, the layers and the "
             "region changed)";
    parsed.convergenceStudy = true;
  }
  else if (a == "--undermine")
  {
    if (!hasValue || !parseWidths(args[++i], parsed.undermineWidths))
      return "--undermine needs undermining widths in mm from 0 to 100, e.g. 0,5,10,20";
  }
  else
    return "unknown option " + a;
  return std::nullopt;
}

std::optional<std::string> parse(const std::vector<std::string>& argv, PlanArgs& parsed)
{
  auto problem = cli::parseCtCommand(
    argv, parsed,
    [&parsed](const std::string& a, const std::vector<std::string>& args,
              std::size_t& i) -> std::optional<std::string> {
      const bool hasValue = i + 1 < args.size();
      if (a == "--procedure")
      {
        if (!hasValue)
          return "--procedure needs an id, e.g. z-plasty";
        parsed.procedure = args[++i];
      }
      else if (a == "--at")
      {
        double theta = 0.0, z = 0.0;
        char tail = 0;
        if (!hasValue || std::sscanf(args[++i].c_str(), "%lf,%lf%c", &theta, &z, &tail) != 2 || !std::isfinite(theta) ||
            !std::isfinite(z))
          return "--at needs THETA,Z: degrees around the head axis and mm along it, e.g. -90,-40";
        parsed.at = std::pair{theta, z};
      }
      else if (a == "--param")
      {
        const std::string text = hasValue ? args[++i] : std::string();
        const auto eq = text.find('=');
        double value = 0.0;
        if (eq == std::string::npos || eq == 0 || !cli::parseNumber(text.substr(eq + 1), value))
          return "--param needs NAME=VALUE, e.g. limb_angle=60";
        parsed.params[text.substr(0, eq)] = value;
      }
      else if (a == "--move" || a == "--offset")
      {
        PlanEdit edit;
        if (!hasValue || !parseEdit(args[++i], a == "--move", edit))
          return a == "--move" ? "--move needs I=THETA,Z: the cut point (from 0) and where it goes in degrees "
                                 "around the head axis and mm along it, e.g. 1=-92.5,3"
                               : "--offset needs V=DU,DV: the border point (from 0) and its move in mm around "
                                 "the head and along the axis, e.g. 2=0,1.5";
        parsed.edits.push_back(edit);
      }
      else if (a == "--undermine-region")
      {
        std::vector<std::pair<double, double>> points;
        if (!hasValue || !parseRegion(args[++i], points))
          return "--undermine-region needs \"THETA,Z;THETA,Z;...\": the corners of the region in degrees around "
                 "the head axis and mm along it, e.g. \"-95,-5;-85,-5;-85,5;-95,5\"";
        parsed.undermineRegions.push_back(std::move(points));
      }
      else if (a == "--replay")
      {
        if (!hasValue)
          return "--replay needs the plan.json that caps plan wrote";
        parsed.replay = fs::path(args[++i]);
      }
      else if (a == "--other-ct")
        parsed.otherCt = true;
      else
        return parseModelOption(a, args, i, parsed);
      return std::nullopt;
    });
  if (problem || parsed.help)
    return problem;
  if (parsed.replay)
  {
    if (!parsed.procedure.empty() || parsed.at || !parsed.params.empty())
      return "--replay rebuilds the plan from its file: leave out --procedure, --at and --param (add --move "
             "or --offset to change it)";
    return std::nullopt;
  }
  if (parsed.otherCt)
    return "--other-ct goes with --replay";
  if (parsed.procedure.empty())
    return "--procedure ID missing: which operation?";
  if (!parsed.at)
    return "--at THETA,Z missing: where on the skin?";
  return std::nullopt;
}

/// The procedure's parameters from the file's units (degrees) to the API's (radians).
std::map<std::string, double> apiValues(const planning::ProcedureTemplate& t,
                                        const std::map<std::string, double>& given)
{
  std::map<std::string, double> values;
  for (const auto& [name, value] : given)
  {
    const auto* p = [&]() -> const planning::ProcedureParameter* {
      for (const auto& q : t.parameters())
        if (q.name == name)
          return &q;
      return nullptr;
    }();
    if (!p)
    {
      std::string known;
      for (const auto& q : t.parameters())
        known += (known.empty() ? "" : ", ") + q.name;
      throw std::invalid_argument("procedure " + t.id() + " has no parameter '" + name + "' (it has " + known + ")");
    }
    values[name] = p->unit == planning::ParameterUnit::Degree ? value * kDegree : value;
  }
  return values;
}

/// Radius (mm on the skin) of the band around the wound where the peak skin stress is taken.
constexpr double kWoundStressRadius = 10.0;

void writeMeasurements(const fs::path& file, const planning::PlanMeasurements& m, const planning::PlanPrediction& p,
                       double excisedVolumeToBone, const planning::WoundStress& stress,
                       const seg::CylindricalPoint& peakAt, const planning::WoundTension& tension)
{
  std::ofstream out(file);
  out << std::setprecision(10) << "quantity,where,chart,skin,unit\n";
  for (const auto& l : m.limbs)
    out << "limb length,p" << l.from << "-p" << l.to << "," << l.chart << "," << l.skin << ",mm\n";
  for (const auto& a : m.limbAngles)
    out << "limb angle,p" << a.point << "," << a.chart / kDegree << "," << a.skin / kDegree << ",deg\n";
  out << "excised area,hole,," << m.excisedArea << ",mm2\n";
  // From the elements of the excised tissue, to the cut's depth, and as a
  // second method the range maps' integral down to the bone.
  out << "excised volume (elements; cut through " << p.cutLayers << " of " << p.layerCount << " layers),hole,,"
      << p.excisedVolume << ",mm3\n";
  out << "excised volume to the bone (range maps),hole,," << excisedVolumeToBone << ",mm3\n";
  out << "wound width before closure,sutures,," << p.maxSutureGapBefore << ",mm\n";
  out << "suture gap after closure,sutures,," << p.maxSutureGap << ",mm\n";
  if (p.gape)
  {
    out << "wound width gaping before suturing,sutures,," << p.gape->widestGaping << ",mm\n";
    out << "mean gape of the wound edges before suturing,skin,," << p.gape->meanOpening << ",mm\n";
    out << "open area of the wound as cut,skin,," << p.gape->openAreaAsCut << ",mm2\n";
    out << "open area of the wound gaping before suturing,skin,," << p.gape->openAreaGaping << ",mm2\n";
  }
  // How far to trust the numbers below (thesis §5.5): the model and its checks.
  const planning::PredictionCheck& c = p.check;
  out << "undermining band,along the sutured edges,," << p.underminingWidth << ",mm\n";
  out << "deep nodes sliding,undermined,," << p.continuum.slidingNodes.size() << ",\n";
  out << "prediction model," << planning::tissueModelId(c.model) << ",,,\n";
  out << "prediction admissible,checks,," << (c.admissible() ? 1 : 0) << ",\n";
  out << "solve converged at full closure,increments,," << (c.converged ? 1 : 0) << ",\n";
  out << "closure reached,increments,," << 100.0 * c.closureFraction << ",%\n";
  out << "load increments,solve,," << c.increments << ",\n";
  out << "increments damped through an instability,solve,," << c.dampedIncrements << ",\n";
  out << "energy dissipated by the damping,of the strain energy,," << 100.0 * c.dissipatedFraction << ",%\n";
  out << "smallest det F,element " << c.deformation.minDetFElement << ",," << c.deformation.minDetF << ",\n";
  out << "largest principal stretch,all integration points,," << c.deformation.maxStretch << ",\n";
  out << "inverted elements,det F <= 0,," << c.deformation.invertedElements << ",\n";
  out << "skin surface crossing itself,triangle pairs,," << c.skinCrossings.crossingPairs << ",\n";
  out << "deep tissue crossing itself,triangle pairs,," << c.tissueCrossings.crossingPairs << ",\n";
  out << "deepest crossing of the deep tissue,no contact in the model,," << c.tissueCrossings.deepest << ",mm\n";
  out << "smallest scaled Jacobian,mesh element " << c.mesh.worstJacobianElement << ",," << c.mesh.minScaledJacobian
      << ",\n";
  out << "largest edge ratio,mesh element " << c.mesh.worstEdgeRatioElement << ",," << c.mesh.maxEdgeRatio << ",\n";
  out << "elements below the scaled Jacobian limit,mesh,," << c.mesh.poorJacobian << ",\n";
  out << "elements below the scaled Jacobian limit as placed,before the interior nodes moved,,"
      << c.nodeOptimization.poorElementsBefore << ",\n";
  out << "interior nodes moved,mesh,," << c.nodeOptimization.movedNodes << ",\n";
  out << "largest interior node move,mesh,," << c.nodeOptimization.largestMove << ",mm\n";
  double largestMove = 0.0;
  for (std::size_t v = 0; v < p.skin.original.size(); ++v)
    largestMove = std::max(largestMove, (p.skin.displaced[v] - p.skin.original[v]).norm());
  out << "largest skin displacement,skin,," << largestMove << ",mm\n";
  out << "closure force (sum over sutures),sutures,," << p.closure.magnitudeSum << ",N\n";
  out << "largest suture force,sutures,," << p.closure.largest << ",N\n";
  // The tension a surgeon reads: per centimetre of each wound line and per stitch.
  const auto csvText = [](const std::string& text) {
    return text.find_first_of(",\"") == std::string::npos
             ? text
             : "\"" + std::regex_replace(text, std::regex("\""), "\"\"") + "\"";
  };
  for (const planning::WoundLineTension& l : tension.lines)
  {
    out << "wound line length," << csvText(l.name) << ",," << l.length << ",mm\n";
    out << "wound tension," << csvText(l.name) << ",," << l.perCentimetre << ",N/cm\n";
    out << "wound tension peak," << csvText(l.name + " between " + l.peakBetween) << ",," << l.peakPerCentimetre
        << ",N/cm\n";
    out << "force per stitch every " << tension.stitchSpacing << " mm," << csvText(l.name) << ",," << l.perStitch
        << ",N\n";
  }
  // §4.7: the skin's nodal stress within stress.radius mm of the hole border.
  const std::string band = "skin within " + std::to_string(int(std::lround(stress.radius))) + " mm of the wound";
  out << "peak skin von Mises near wound," << band << ",," << 1e3 * stress.peakVonMises << ",kPa\n";
  out << "peak skin von Mises theta,skin vertex " << stress.vertex << ",," << peakAt.theta / kDegree << ",deg\n";
  out << "peak skin von Mises z,skin vertex " << stress.vertex << ",," << peakAt.z << ",mm\n";
  out << "peak skin von Mises distance from wound,skin vertex " << stress.vertex << "," << stress.distance << ",,mm\n";
  out << "peak skin max principal stress near wound," << band << ",," << 1e3 * stress.peakMaxPrincipal << ",kPa\n";
  out << "mean skin von Mises near wound," << band << ",," << 1e3 * stress.meanVonMises << ",kPa\n";
  if (p.zPlasty)
  {
    out << "z-plasty gain predicted,central limb,," << 100.0 * p.zPlasty->predicted.fraction << ",%\n";
    out << "z-plasty gain theoretical (Fig. 2.2),central limb,," << 100.0 * p.zPlasty->theoretical << ",%\n";
  }
  if (!out)
    throw std::runtime_error("cannot write " + file.string() + ": check the folder's permissions and space");
}

/// One `caps plan` run, step by step: run() is the table of contents.
class PlanRun
{
public:
  PlanRun(IncisionLogic& logic, PlanArgs args, std::ostream& out, std::ostream& err)
    : logic_(logic), args_(std::move(args)), out_(out), err_(err)
  {}

  void run()
  {
    readTheProcedureOrRecipe(); // a typo stops us before the long part
    cli::makeOutputFolder(args_.out);
    readTheCt();
    takeTheRangeMaps();
    recordThePlan();
    refuseACutOnUnsoundSkin();
    saveTheRecipe(); // before the long solve: the plan is kept even if the prediction fails
    predict();
    printThePrediction();
    writeTheFiles();
    if (!args_.undermineWidths.empty())
      studyTheUndermining();
    if (args_.convergenceStudy)
      studyTheConvergence();
  }

  /// A large-deformation solve that stopped short of the closure or gave a
  /// deformation that is not a body (the linear preview's own failure is a
  /// warning: it is the preview, and the large-deformation model is the cure).
  bool failedItsChecks() const
  {
    return prediction_.check.model == planning::TissueModel::LargeDeformation && !prediction_.check.admissible();
  }

private:
  /// The procedure and its values, or the plan file to replay (its
  /// procedures checked).
  void readTheProcedureOrRecipe()
  {
    if (args_.replay)
    {
      replay_ = planning::readRecipe(*args_.replay);
      for (const auto& operation : replay_->operations)
        if (const auto* place = std::get_if<planning::PlaceProcedure>(&operation))
          planning::findProcedure(logic_.procedures(), place->procedure);
      return;
    }
    const planning::ProcedureTemplate& procedure = planning::findProcedure(logic_.procedures(), args_.procedure);
    // Every value recorded, defaults too: a default changed in the
    // procedure file later does not change the replayed plan.
    values_ = procedure.resolveValues(apiValues(procedure, args_.params)); // range errors now
  }

  /// The CT, and for a replay the check that it is the one the plan was
  /// made on (refused unless --other-ct) by this version of CAPS (warned).
  void readTheCt()
  {
    args_.read.progress = cli::consoleProgress(err_);
    volume_ = cli::loadCt(logic_, args_.ct, args_.read, err_);
    ctHash_ = planning::ctContentHash(volume_->image());
    if (!replay_)
      return;
    const std::string file = args_.replay->string();
    if (replay_->ctSha256 != ctHash_)
    {
      const std::string made =
        replay_->ctSha256.empty() ? std::string("a CT it does not name") : "a CT of SHA-256 " + replay_->ctSha256;
      if (!args_.otherCt)
        throw std::invalid_argument(file + " was made on " + made + ", not on this CT (SHA-256 " + ctHash_ +
                                    "): another scan or another patient. Replay it on the CT it was made on, "
                                    "or give --other-ct to apply its operations to this CT anyway.");
      err_ << "caps plan: warning: " << file << " was made on " << made
           << "; its operations are applied to this CT (--other-ct), the prediction is a new one.\n";
    }
    if (replay_->softwareVersion != planning::softwareVersion())
      err_ << "caps plan: warning: " << file << " was made by CAPS "
           << (replay_->softwareVersion.empty() ? std::string("of an unknown version") : replay_->softwareVersion)
           << ", this is CAPS " << planning::softwareVersion()
           << ": the plan is rebuilt from the same operations, but the prediction may differ from the one made "
              "then.\n";
  }

  /// The range maps: those already in the scene when it holds this one CT
  /// (`caps demo` made them a step earlier), else made now.
  void takeTheRangeMaps()
  {
    const auto [skinNode, boneNode] = RangeMapLogic::newestMaps(logic_.scene());
    if (skinNode && boneNode && logic_.scene().nodesOfType(NodeType::Volume).size() == 1)
    {
      maps_.skin = RangeMapLogic::toRangeMap(*skinNode);
      maps_.bone = RangeMapLogic::toRangeMap(*boneNode);
      skinMapId_ = skinNode->id();
      return;
    }
    RangeMapLogic rangeMaps(logic_.scene());
    skinMapId_ = rangeMaps.run(*volume_, RangeMapLogic::Parameters{}, cli::consoleProgress(err_), &maps_).skinId;
  }

  /// The plan as the operations that make it, each checked as it is
  /// applied: the placed procedure or the replayed operations, then the
  /// edits and the undermined regions of the command line.
  void recordThePlan()
  {
    const seg::RangeMap& skin = maps_.skin;
    recorded_.emplace(ctHash_);
    if (replay_)
    {
      try
      {
        for (const auto& operation : replay_->operations)
          recorded_->apply(operation, skin, logic_.procedures());
      }
      catch (const planning::RecipeError& e)
      {
        throw planning::RecipeError(e.operation(), args_.replay->string() + ": " + e.what());
      }
    }
    else
      recorded_->apply(
        planning::PlaceProcedure{args_.procedure, {args_.at->first * kDegree, args_.at->second}, values_}, skin,
        logic_.procedures());
    for (const PlanEdit& e : args_.edits)
      if (e.move)
        recorded_->apply(
          planning::MoveCutPoint{e.index, planning::normalizedFromSkinPoint(skin.frame(), {e.a * kDegree, e.b})}, skin,
          logic_.procedures());
      else
        recorded_->apply(planning::OffsetBorderPoint{e.index, {e.a, e.b}}, skin, logic_.procedures());
    for (const auto& points : args_.undermineRegions)
    {
      planning::UndermineRegion region;
      for (const auto& [theta, z] : points)
        region.region.push_back(planning::normalizedFromSkinPoint(skin.frame(), {theta * kDegree, z}));
      recorded_->apply(region, skin, logic_.procedures());
    }
  }

  /// No cut through skin the CT's metal streaks spoil, or over skin pressed
  /// against the head holder: its skin and bone there are artefacts
  /// (planning::cutInMetalStreaks, planning::cutAgainstAnObject).
  void refuseACutOnUnsoundSkin()
  {
    const RangeMapLogic rangeMaps(logic_.scene());
    std::string why =
      planning::cutInMetalStreaks(recorded_->plan(), maps_.skin, rangeMaps.metalOf(*volume_), volume_->image());
    if (why.empty())
      why = planning::cutAgainstAnObject(recorded_->plan(), maps_.skin,
                                         rangeMaps.againstAnObject(*volume_, maps_.skin.frame()));
    if (!why.empty())
      throw std::invalid_argument("The plan cannot be cut where it is: " + why + ".");
  }

  /// plan.json: the operations, with the prediction's element size and cut
  /// depth so a replay meshes the same.
  void saveTheRecipe()
  {
    const double elementSize =
      args_.elementSize.value_or(replay_ && replay_->elementSize > 0.0 ? replay_->elementSize : 2.0);
    const std::optional<int> cutLayers = args_.cutLayers ? args_.cutLayers
                                         : replay_       ? replay_->cutLayers
                                                         : std::nullopt;
    const planning::TissueModel model =
      args_.model.value_or(replay_ ? replay_->model : planning::TissueModel::LargeDeformation);
    saved_ = recorded_->recipe();
    saved_.elementSize = elementSize;
    saved_.cutLayers = cutLayers;
    saved_.model = model;
    saved_.underminingWidth = args_.underminingWidth ? args_.underminingWidth
                              : replay_              ? replay_->underminingWidth
                                                     : std::nullopt;
    saved_.preTension = args_.preTension ? *args_.preTension
                        : replay_        ? replay_->preTension
                                         : std::optional(kDefaultPreTension);
    planning::writeRecipe(saved_, args_.out / "plan.json");
    options_.underminingWidth = saved_.underminingWidth;
    options_.elementSize = elementSize;
    options_.cutLayers = cutLayers;
    options_.model = model;
    options_.threads = 2;
  }

  /// The measurements on the skin, the prediction and its wound stress.
  void predict()
  {
    const planning::IncisionPlan& plan = recorded_->plan();
    procedure_ = &planning::findProcedure(logic_.procedures(), plan.procedure());
    measured_ = planning::measurePlan(plan, maps_.skin);
    tensionTheSkin();
    options_.progress = cli::consoleProgress(err_);
    prediction_ = planning::simulatePlan(maps_.skin, maps_.bone, plan, options_);
    options_.progress = {};
    woundStress_ = planning::woundSkinStress(prediction_, kWoundStressRadius);
    tension_ = planning::woundTension(prediction_, plan, args_.stitchSpacing);
    peakAt_ = maps_.skin.frame().toCylindrical(woundStress_.original);
    // plan.json says how the prediction checked out, and what holds the wound closed
    saved_.prediction = prediction_.check;
    saved_.closure = planning::closureRecordOf(prediction_, woundStress_, tension_);
    planning::writeRecipe(saved_, args_.out / "plan.json");
    excisedVolume_ = planning::excisedVolume(plan, maps_.skin, maps_.bone, options_.noBoneDepth);
    // The meshed region cut short (a shape the mesher could not grow round,
    // or the end of the scan) changes the prediction: say so.
    if (!prediction_.surface.message.empty())
      err_ << "caps plan: note: " << prediction_.surface.message
           << (prediction_.surface.stoppedEarly ? "; the skin beyond is left out of the model, which makes the "
                                                  "closure look easier than it is: move the plan points a little "
                                                  "and run again"
                                                : "")
           << "\n";
  }

  /// The skin's pre-tension of the plan (saved_.preTension); the
  /// simulation places its directions (the tension lines of this face).
  void tensionTheSkin()
  {
    options_.preTension.reset();
    if (!saved_.preTension)
      return;
    planning::SkinPreTension tension;
    tension.alongLines = (*saved_.preTension)[0];
    tension.acrossLines = (*saved_.preTension)[1];
    options_.preTension = tension;
  }

  /// "Undermined: 12.0 mm band along the sutured edges (the procedure's),
  /// 1 region; 310 deep nodes slide on the deep plane".
  void printTheUndermining()
  {
    const planning::IncisionPlan& plan = recorded_->plan();
    const planning::PlanPrediction& p = prediction_;
    const double band = planning::underminingWidthFor(options_, plan);
    out_ << "Undermined: ";
    if (band > 0.0)
      out_ << std::fixed << std::setprecision(1) << band << " mm band along the sutured edges ("
           << (options_.underminingWidth ? "as asked" : "the procedure's default") << ")";
    else
      out_ << "no band" << (options_.underminingWidth ? "" : " (the procedure states none)");
    if (!plan.underminedRegions().empty())
      out_ << ", " << plan.underminedRegions().size() << " region(s)";
    if (p.continuum.underminedNodes.empty())
      out_ << "; the bone holds the whole deep face\n";
    else
      out_ << "; " << p.continuum.underminedNodes.size() << " deep nodes freed, " << p.continuum.slidingNodes.size()
           << " of them sliding on the deep plane\n";
  }

  void printThePrediction()
  {
    const planning::IncisionPlan& plan = recorded_->plan();
    const planning::PlanPrediction& p = prediction_;
    out_ << std::fixed << std::setprecision(1);
    if (replay_)
      out_ << "Replayed " << replay_->operations.size() << " operations of " << args_.replay->string() << "\n";
    out_ << "Plan: " << procedure_->title() << " at theta " << plan.centre().theta / kDegree << " deg, z "
         << plan.centre().z << " mm, " << recorded_->recipe().operations.size() << " operations\n";
    for (const auto& l : measured_.limbs)
      out_ << "  limb p" << l.from << "-p" << l.to << ": " << l.skin << " mm on the skin\n";
    for (const auto& a : measured_.limbAngles)
      out_ << "  angle at p" << a.point << ": " << a.skin / kDegree << " deg on the skin\n";
    if (measured_.excisedArea > 0.0)
      out_ << "  excised area: " << measured_.excisedArea << " mm2, volume " << p.excisedVolume << " mm3 (elements; "
           << excisedVolume_ << " mm3 to the bone by the range maps)\n";
    if (p.cutLayers != p.layerCount)
      out_ << "  cut through " << p.cutLayers << " of " << p.layerCount << " tissue layers"
           << (options_.cutLayers ? "" : " (the procedure's depth)") << ": the tissue below stays whole\n";
    out_ << "Tissue model: " << planning::tissueModelDescription(p.check.model) << "\n";
    out_ << "Model: " << p.continuum.mesh.nodeCount() << " nodes, " << p.continuum.mesh.elements.size() << " elements, "
         << p.dofCount << " DOF (" << p.reducedDofCount << " free); mesh " << std::setprecision(3) << p.times.mesh
         << " s, assemble " << p.times.assemble << " s, factor " << p.times.factor << " s, solve " << p.times.solve
         << " s\n";
    printTheUndermining();
    printTheChecks();
    printTheGape();
    out_ << std::setprecision(2) << "Wound " << p.maxSutureGapBefore << " mm wide before, sutures within "
         << std::scientific << p.maxSutureGap << std::fixed << " mm after closure\n";
    out_ << std::setprecision(3) << "Closure force: " << p.closure.magnitudeSum
         << " N over all sutures, largest suture " << p.closure.largest << " N\n";
    printTheWoundTension();
    const planning::WoundStress& w = woundStress_;
    out_ << std::setprecision(1) << "Skin stress within " << kWoundStressRadius << " mm of the wound: peak von Mises "
         << 1e3 * w.peakVonMises << " kPa at theta " << peakAt_.theta / kDegree << " deg, z " << peakAt_.z << " mm ("
         << w.distance << " mm from the wound edge), largest principal " << 1e3 * w.peakMaxPrincipal
         << " kPa, mean von Mises " << 1e3 * w.meanVonMises << " kPa\n";
    if (p.zPlasty)
      out_ << std::setprecision(1) << "Z-plasty gain in length: predicted " << 100.0 * p.zPlasty->predicted.fraction
           << " %, theoretical " << 100.0 * p.zPlasty->theoretical << " % (Fig. 2.2)\n";
    out_.unsetf(std::ios::floatfield);
  }

  /// The skin's pre-tension and how far the wound gapes under it.
  void printTheGape()
  {
    const planning::PlanPrediction& p = prediction_;
    if (p.preTension.empty())
    {
      out_ << "Skin pre-tension: none (slack skin, as the thesis): the wound does not gape\n";
      return;
    }
    out_ << "Skin pre-tension: " << p.preTension << "\n";
    if (!p.gape)
      return;
    out_ << std::setprecision(1) << "Wound gaping before it is sutured: open " << p.gape->openAreaGaping << " mm² ("
         << p.gape->openAreaAsCut << " mm² as cut); the sides to be sutured " << std::setprecision(2)
         << p.gape->widestGaping << " mm apart at most (" << p.gape->widestAsCut << " mm as cut), "
         << p.gape->meanOpening << " mm further apart on average\n";
    if (!p.gape->problem.empty())
      out_ << "WARNING (gaping wound): " << p.gape->problem << "\n";
  }

  /// Per wound line, the tension across it per centimetre and per stitch.
  void printTheWoundTension()
  {
    out_ << std::setprecision(2) << "Wound tension across each line (all layers sewn), a stitch every "
         << tension_.stitchSpacing << " mm:\n";
    for (const planning::WoundLineTension& l : tension_.lines)
      out_ << "  " << l.name << ": " << std::setprecision(1) << l.length << " mm closed, " << std::setprecision(2)
           << l.perCentimetre << " N/cm (peak " << l.peakPerCentimetre << " N/cm between " << l.peakBetween << "), "
           << l.perStitch << " N per stitch (peak " << l.peakPerStitch << " N), " << l.stitches << " stitches\n";
  }

  /// How far to trust what follows: the solve and det F (thesis §5.5).
  void printTheChecks()
  {
    out_ << "Checks: " << planning::checkSummary(prediction_.check) << "\n";
    if (const std::string warning = planning::checkWarning(prediction_.check); !warning.empty())
      out_ << warning << "\n";
    if (!prediction_.check.caveat.empty())
      out_ << "Caveat: " << prediction_.check.caveat << "\n";
  }

  /// measurements.csv, the display surfaces (§4.7: subdivided skin faces
  /// with range detail, coloured by the tissue a little under the skin, the
  /// CT has no colour), the prediction in the scene (`caps demo` saves it,
  /// numbered among the plans there) and model.vtu.
  void writeTheFiles()
  {
    const planning::IncisionPlan& plan = recorded_->plan();
    writeMeasurements(args_.out / "measurements.csv", measured_, prediction_, excisedVolume_, woundStress_, peakAt_,
                      tension_);
    const seg::ColourMap shade = seg::skinShadeFromCt(volume_->image(), maps_.skin);
    const planning::PlanDisplay display = planning::buildPlanDisplay(prediction_, maps_.skin, &shade);
    planning::writePlanDisplay(display, args_.out / "skin-before.vtp", args_.out / "skin-after.vtp");
    const std::string name =
      procedure_->title() + " " + std::to_string(logic_.scene().nodesOfType(NodeType::Plan).size() + 1);
    logic_.addPrediction(name, plan, saved_, prediction_, display, skinMapId_);
    fem::writeVtu((args_.out / "model.vtu").string(), prediction_.continuum.mesh, modelArrays(prediction_),
                  elementArrays(prediction_));
    for (const char* file : {"plan.json", "measurements.csv", "skin-before.vtp", "skin-after.vtp", "model.vtu"})
      out_ << "wrote " << (args_.out / file).string() << "\n";
  }

  /// How much the numbers depend on the model's own choices (thesis §5.5):
  /// planning::studyConvergence(), as convergence.csv and a table.
  void studyTheConvergence()
  {
    out_ << "Convergence and sensitivity study (skin stress within " << std::lround(kWoundStressRadius)
         << " mm of the wound; the peak at a wound corner is singular and grows as the mesh is refined, so the "
            "band mean is the stress to read):\n";
    const planning::ConvergenceStudy study = planning::studyConvergence(
      maps_.skin, maps_.bone, recorded_->plan(), options_, {}, kWoundStressRadius, cli::consoleProgress(err_));
    const fs::path csv = args_.out / "convergence.csv";
    std::ofstream table(csv);
    table << std::setprecision(10)
          << "series,level,solved,tension (N/cm),change (%),mean wound stress (kPa),change (%),peak wound stress "
             "(kPa; singular),z-plasty gain (%),change (%),largest displacement (mm),change (%),closure force "
             "(sum over node sutures) (N),change (%),smallest det F,problem\n";
    const auto shown = [](double v, int digits) {
      std::ostringstream text;
      if (std::isnan(v))
        text << "-";
      else
        text << std::fixed << std::setprecision(digits) << v;
      return text.str();
    };
    for (const planning::ConvergenceRow& r : study.rows)
    {
      table << r.series << "," << r.value << "," << (r.solved ? 1 : 0) << "," << r.tensionPerCentimetre << ","
            << shown(r.tensionChange, 3) << "," << r.meanWoundStressKPa << "," << shown(r.meanStressChange, 3) << ","
            << r.peakWoundStressKPa << "," << shown(r.gainPercent, 4) << "," << shown(r.gainChange, 3) << ","
            << r.largestDisplacement << "," << shown(r.displacementChange, 3) << "," << r.closureForce << ","
            << shown(r.forceChange, 3) << "," << r.minDetF << ",\"" << r.problem << "\"\n";
      out_ << "  " << r.series << " " << shown(r.value, 1) << ": ";
      if (!r.computed)
      {
        out_ << "not solved: " << r.problem << "\n";
        continue;
      }
      out_ << shown(r.tensionPerCentimetre, 3) << " N/cm (" << shown(r.tensionChange, 1) << " %), mean stress "
           << shown(r.meanWoundStressKPa, 1) << " kPa (" << shown(r.meanStressChange, 1) << " %), peak "
           << shown(r.peakWoundStressKPa, 1) << " kPa, gain " << shown(r.gainPercent, 1) << " % ("
           << shown(r.gainChange, 1) << " %), largest displacement " << shown(r.largestDisplacement, 2) << " mm ("
           << shown(r.displacementChange, 1) << " %)" << (r.solved ? "" : "; NOT A PREDICTION: " + r.problem) << "\n";
    }
    if (!table)
      throw std::runtime_error("cannot write " + csv.string() + ": check the folder's permissions and space");
    out_ << "wrote " << csv.string() << "\n";
  }

  /// The surgeon's question: how far must I undermine? The same plan and
  /// mesh, the bone released under a band around the sutured edges
  /// (planning::studyUndermining()), as undermining.csv and a plot.
  void studyTheUndermining()
  {
    const planning::IncisionPlan& plan = recorded_->plan();
    out_ << "Undermining study (closure force and peak skin stress within " << std::lround(kWoundStressRadius)
         << " mm of the wound against width):\n";
    const planning::UnderminingStudy study =
      planning::studyUndermining(maps_.skin, maps_.bone, plan, options_, args_.undermineWidths, kWoundStressRadius);
    if (study.regionRadius > planning::SimulationOptions{}.regionRadius)
      out_ << "  (meshed region " << study.regionRadius << " mm around the wound, for the widest band)\n";
    const fs::path csv = args_.out / "undermining.csv";
    std::ofstream table(csv);
    table << std::setprecision(10)
          << "undermining width (mm),released bone nodes,closure force (sum over sutures) (N),"
             "largest suture force (N),suture gap after closure (mm),peak skin von Mises near wound (kPa),"
             "mean skin von Mises near wound (kPa)\n";
    render::PlotSeries force{"closure force, sum over sutures (N)", {}, {}, 0x1f4e9c};
    render::PlotSeries stress{"peak skin von Mises within " + std::to_string(std::lround(kWoundStressRadius)) +
                                " mm of the wound (kPa)",
                              {},
                              {},
                              0xc0392b};
    for (const planning::UnderminingStudyRow& row : study.rows)
    {
      table << row.width << "," << row.releasedBoneNodes << "," << row.closureForce << "," << row.largestSutureForce
            << "," << row.sutureGap << "," << row.peakVonMisesKPa << "," << row.meanVonMisesKPa << "\n";
      force.x.push_back(row.width);
      force.y.push_back(row.closureForce);
      stress.x.push_back(row.width);
      stress.y.push_back(row.peakVonMisesKPa);
      out_ << std::fixed << std::setprecision(1) << "  " << row.width << " mm: " << std::setprecision(3)
           << row.closureForce << " N, largest suture " << row.largestSutureForce << " N, peak skin stress "
           << std::setprecision(1) << row.peakVonMisesKPa << " kPa (mean " << row.meanVonMisesKPa << " kPa)\n";
      out_.unsetf(std::ios::floatfield);
    }
    if (!table)
      throw std::runtime_error("cannot write " + csv.string() + ": check the folder's permissions and space");
    out_ << "wrote " << csv.string() << "\n";
    std::ostringstream title;
    title << std::fixed << std::setprecision(1) << "Undermining: " << procedure_->title() << " at theta "
          << plan.centre().theta / kDegree << " deg, z " << plan.centre().z << " mm";
    render::XyPlot plot;
    plot.title = title.str();
    plot.xLabel = "undermining width (mm)";
    plot.series = {force, stress};
    render::writeXyPlotPng(plot, args_.out / "undermining.png");
    out_ << "wrote " << (args_.out / "undermining.png").string() << "\n";
  }

  IncisionLogic& logic_;
  PlanArgs args_;
  std::ostream& out_;
  std::ostream& err_;
  std::optional<planning::PlanRecipe> replay_;
  std::map<std::string, double> values_;
  VolumeNode* volume_ = nullptr;
  std::string ctHash_;
  RangeMapOutput maps_;
  NodeId skinMapId_;
  std::optional<planning::RecordedPlan> recorded_;
  planning::PlanRecipe saved_;
  planning::SimulationOptions options_;
  const planning::ProcedureTemplate* procedure_ = nullptr;
  planning::PlanMeasurements measured_;
  planning::PlanPrediction prediction_;
  double excisedVolume_ = 0.0;
  planning::WoundStress woundStress_;
  planning::WoundTension tension_;
  seg::CylindricalPoint peakAt_;
};

int runPlan(ModuleLogic& moduleLogic, const std::vector<std::string>& argv, std::ostream& out, std::ostream& err)
{
  return cli::runCommand<PlanArgs>("plan", kPlanUsage, argv, out, err, parse, [&](PlanArgs& args) {
    try
    {
      PlanRun run(static_cast<IncisionLogic&>(moduleLogic), std::move(args), out, err);
      run.run();
      return run.failedItsChecks() ? 3 : 0;
    }
    catch (const fem::ElementError& e)
    {
      err << "caps plan: the tissue under the plan is too uneven for its mesh (" << e.what()
          << "). Try a smaller --element-size, or move the plan where the skin and bone are smoother.\n";
      return 1;
    }
  });
}

} // namespace

std::vector<ModuleCommand> planCommands()
{
  return {{"plan", "place a procedure on the skin of a CT and predict the result (measurements, VTP, VTU)", kPlanUsage,
           runPlan}};
}

} // namespace caps
