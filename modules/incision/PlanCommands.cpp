// `caps plan`: a procedure placed on a patient's skin and simulated end to
// end (issue 5 item 7): CT → skin and bone range maps → plan → measurements
// on the skin → mesh skin to bone → sutures closed → predicted skin.

#include "modules/incision/PlanCommands.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <numbers>

#include <vtkCellArray.h>
#include <vtkDoubleArray.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include "fem/ElementGeometry.h"
#include "fem/VtuWriter.h"
#include "modules/incision/IncisionLogic.h"
#include "modules/incision/PlanSimulation.h"
#include "modules/rangemap/RangeMapLogic.h"
#include "modules/segment/SegmentCommands.h"
#include "scene/RangeMapNode.h"
#include "scene/Scene.h"
#include "scene/VolumeNode.h"

namespace fs = std::filesystem;

namespace caps {
namespace {

constexpr double kDegree = std::numbers::pi / 180.0;

const char* kPlanUsage =
  "usage: caps plan CT --procedure ID --at THETA,Z --out DIR [--param NAME=VALUE ...]\n"
  "                 [--element-size MM] [--series N|UID]\n"
  "\n"
  "Places a procedure on the patient's skin and predicts the result (thesis §4.4-4.6):\n"
  "segments the CT, unwraps skin and bone into range maps, places the procedure's cut\n"
  "centred at THETA (degrees around the head axis, -90 = the front of the face) and Z\n"
  "(mm along the axis, as `caps rangemap` prints them), measures it on the skin, meshes\n"
  "the skin down to the bone, closes the sutures and writes into DIR:\n"
  "  measurements.csv     limb lengths and angles on the skin, excised area, Z-plasty gain\n"
  "  skin-before.vtp      the meshed skin around the wound before the operation\n"
  "  skin-after.vtp       the same surface after it (displacement in mm as point data)\n"
  "  model.vtu            the finite element model with its displacements\n"
  "\n"
  "  --procedure ID       one of data/procedures/ (e.g. z-plasty, elliptical-excision)\n"
  "  --param NAME=VALUE   a parameter of the procedure in its file's units (mm, degrees,\n"
  "                       ratio); the others take their defaults\n"
  "  --element-size MM    element size at the wound (default 2)\n"
  "  --series N|UID       in a folder with several series, the one to use\n"
  "\n"
  "The tissue is linear elastic with assumed moduli (skin 0.15, fat 0.01, muscle\n"
  "0.05 MPa, Poisson 0.45), the bone fixed: a first prediction, not a measurement.\n"
  "Exit status: 0 when written, 1 when the CT or the plan cannot be used (the message\n"
  "says why), 2 on wrong usage.\n";

struct PlanArgs : cli::CtCommandArgs
{
  std::string procedure;
  std::optional<std::pair<double, double>> at; ///< degrees, mm
  std::map<std::string, double> params;        ///< file units
  double elementSize = 2.0;
};

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
        if (!hasValue || std::sscanf(args[++i].c_str(), "%lf,%lf%c", &theta, &z, &tail) != 2 ||
            !std::isfinite(theta) || !std::isfinite(z))
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
      else if (a == "--element-size")
      {
        if (!hasValue || !cli::parseNumber(args[++i], parsed.elementSize) || parsed.elementSize <= 0.2 ||
            parsed.elementSize > 20.0)
          return "--element-size needs a length in mm between 0.2 and 20";
      }
      else
        return "unknown option " + a;
      return std::nullopt;
    });
  if (problem || parsed.help)
    return problem;
  if (parsed.procedure.empty())
    return "--procedure ID missing: which operation?";
  if (!parsed.at)
    return "--at THETA,Z missing: where on the skin?";
  return std::nullopt;
}

/// The procedure's parameters from the file's units (degrees) to the API's (radians).
std::map<std::string, double> apiValues(const incision::ProcedureTemplate& t,
                                        const std::map<std::string, double>& given)
{
  std::map<std::string, double> values;
  for (const auto& [name, value] : given)
  {
    const auto* p = [&]() -> const incision::ProcedureParameter* {
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
      throw std::invalid_argument("procedure " + t.id() + " has no parameter '" + name + "' (it has " +
                                  known + ")");
    }
    values[name] = p->unit == incision::ParameterUnit::Degree ? value * kDegree : value;
  }
  return values;
}

vtkSmartPointer<vtkPolyData> skinSurface(const incision::DisplacedSkin& skin, bool after)
{
  auto points = vtkSmartPointer<vtkPoints>::New();
  points->SetDataTypeToDouble();
  auto displacement = vtkSmartPointer<vtkDoubleArray>::New();
  displacement->SetName("displacement_mm");
  displacement->SetNumberOfComponents(3);
  for (std::size_t v = 0; v < skin.original.size(); ++v)
  {
    const Eigen::Vector3d& p = after ? skin.displaced[v] : skin.original[v];
    points->InsertNextPoint(p.data());
    const Eigen::Vector3d d = skin.displaced[v] - skin.original[v];
    displacement->InsertNextTuple(d.data());
  }
  auto polys = vtkSmartPointer<vtkCellArray>::New();
  for (const auto& polygon : skin.polygons)
  {
    polys->InsertNextCell(vtkIdType(polygon.size()));
    for (int v : polygon)
      polys->InsertCellPoint(v);
  }
  auto surface = vtkSmartPointer<vtkPolyData>::New();
  surface->SetPoints(points);
  surface->SetPolys(polys);
  surface->GetPointData()->AddArray(displacement);
  return surface;
}

void writeMeasurements(const fs::path& file, const incision::PlanMeasurements& m,
                       const incision::PlanPrediction& p)
{
  std::ofstream out(file);
  out << std::setprecision(10) << "quantity,where,chart,skin,unit\n";
  for (const auto& l : m.limbs)
    out << "limb length,p" << l.from << "-p" << l.to << "," << l.chart << "," << l.skin << ",mm\n";
  for (const auto& a : m.limbAngles)
    out << "limb angle,p" << a.point << "," << a.chart / kDegree << "," << a.skin / kDegree << ",deg\n";
  out << "excised area,hole,," << m.excisedArea << ",mm2\n";
  out << "wound width before closure,sutures,," << p.maxSutureGapBefore << ",mm\n";
  out << "suture gap after closure,sutures,," << p.maxSutureGap << ",mm\n";
  if (p.zPlasty)
  {
    out << "z-plasty gain predicted,central limb,," << 100.0 * p.zPlasty->predicted.fraction << ",%\n";
    out << "z-plasty gain theoretical (Fig. 2.2),central limb,," << 100.0 * p.zPlasty->theoretical << ",%\n";
  }
  if (!out)
    throw std::runtime_error("cannot write " + file.string() + ": check the folder's permissions and space");
}

int runPlan(ModuleLogic& moduleLogic, const std::vector<std::string>& argv, std::ostream& out,
            std::ostream& err)
{
  PlanArgs args;
  if (auto problem = parse(argv, args))
  {
    err << "caps plan: " << *problem << "\n" << kPlanUsage;
    return 2;
  }
  if (args.help)
  {
    out << kPlanUsage;
    return 0;
  }
  auto& logic = static_cast<IncisionLogic&>(moduleLogic);
  try
  {
    // The procedure and its values first: a typo stops us before the long part.
    const incision::ProcedureTemplate* procedure = logic.procedures().find(args.procedure);
    if (!procedure)
    {
      std::string known;
      for (const auto& t : logic.procedures().procedures())
        known += (known.empty() ? "" : ", ") + t.id();
      throw std::invalid_argument("there is no procedure '" + args.procedure + "' (there are: " + known + ")");
    }
    const auto values = apiValues(*procedure, args.params);
    procedure->resolveValues(values); // range errors now
    cli::makeOutputFolder(args.out);

    args.read.progress = cli::consoleProgress(err);
    VolumeNode* volume = cli::loadCt(logic, args.ct, args.read, err);
    // The range maps: those already in the scene when it holds this one CT
    // (`caps demo` made them a step earlier), else made now.
    RangeMapOutput maps;
    {
      const RangeMapNode* skinNode = nullptr;
      const RangeMapNode* boneNode = nullptr;
      for (Node* n : logic.scene().nodesOfType(NodeType::RangeMap))
      {
        const auto* map = static_cast<const RangeMapNode*>(n);
        if (map->role() == "skin")
          skinNode = map;
        else if (map->role() == "bone")
          boneNode = map;
      }
      if (skinNode && boneNode && logic.scene().nodesOfType(NodeType::Volume).size() == 1)
      {
        maps.skin = RangeMapLogic::toRangeMap(*skinNode);
        maps.bone = RangeMapLogic::toRangeMap(*boneNode);
      }
      else
      {
        RangeMapLogic rangeMaps(logic.scene());
        rangeMaps.run(*volume, RangeMapLogic::Parameters{}, cli::consoleProgress(err), &maps);
      }
    }

    const incision::SkinPoint at{args.at->first * kDegree, args.at->second};
    const incision::IncisionPlan plan = logic.placeProcedure(args.procedure, maps.skin, at, values);
    const incision::PlanMeasurements measured = incision::measurePlan(plan, maps.skin);
    incision::SimulationOptions options;
    options.elementSize = args.elementSize;
    options.threads = 2;
    const incision::PlanPrediction prediction = incision::simulatePlan(maps.skin, maps.bone, plan, options);

    out << std::fixed << std::setprecision(1);
    out << "Plan: " << procedure->title() << " at theta " << args.at->first << " deg, z " << args.at->second
        << " mm\n";
    for (const auto& l : measured.limbs)
      out << "  limb p" << l.from << "-p" << l.to << ": " << l.skin << " mm on the skin\n";
    for (const auto& a : measured.limbAngles)
      out << "  angle at p" << a.point << ": " << a.skin / kDegree << " deg on the skin\n";
    if (measured.excisedArea > 0.0)
      out << "  excised area: " << measured.excisedArea << " mm2\n";
    out << "Model: " << prediction.continuum.mesh.nodeCount() << " nodes, "
        << prediction.continuum.mesh.elements.size() << " elements, " << prediction.dofCount << " DOF ("
        << prediction.reducedDofCount << " free); mesh " << std::setprecision(3) << prediction.times.mesh
        << " s, assemble " << prediction.times.assemble << " s, factor " << prediction.times.factor
        << " s, solve " << prediction.times.solve << " s\n";
    out << std::setprecision(2) << "Wound " << prediction.maxSutureGapBefore << " mm wide before, sutures within "
        << std::scientific << prediction.maxSutureGap << std::fixed << " mm after closure\n";
    if (prediction.zPlasty)
      out << std::setprecision(1) << "Z-plasty gain in length: predicted " << 100.0 * prediction.zPlasty->predicted.fraction
          << " %, theoretical " << 100.0 * prediction.zPlasty->theoretical << " % (Fig. 2.2)\n";
    out.unsetf(std::ios::floatfield);

    writeMeasurements(args.out / "measurements.csv", measured, prediction);
    cli::writeVtp(skinSurface(prediction.skin, false), args.out / "skin-before.vtp");
    cli::writeVtp(skinSurface(prediction.skin, true), args.out / "skin-after.vtp");
    const Eigen::Map<const Eigen::Matrix3Xd> u(prediction.displacements.data(), 3,
                                               prediction.displacements.size() / 3);
    fem::writeVtu((args.out / "model.vtu").string(), prediction.continuum.mesh,
                  {{"displacement_mm", Eigen::MatrixXd(u)}});
    for (const char* file : {"measurements.csv", "skin-before.vtp", "skin-after.vtp", "model.vtu"})
      out << "wrote " << (args.out / file).string() << "\n";
    return 0;
  }
  catch (const fem::ElementError& e)
  {
    err << "caps plan: the tissue under the plan is too uneven for its mesh (" << e.what()
        << "). Try a smaller --element-size, or move the plan where the skin and bone are smoother.\n";
    return 1;
  }
  catch (const std::exception& e)
  {
    err << "caps plan: " << e.what() << "\n";
    return 1;
  }
}

} // namespace

std::vector<ModuleCommand> planCommands()
{
  return {{"plan", "place a procedure on the skin of a CT and predict the result (measurements, VTP, VTU)",
           kPlanUsage, runPlan}};
}

} // namespace caps
