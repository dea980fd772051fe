#include "planning/PlanRecipe.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>

#include <QByteArray>
#include <QCryptographicHash>

#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkMatrix3x3.h>
#include <vtkPointData.h>

#include "planning/Undermining.h"

#ifndef CAPS_VERSION
#error "CAPS_VERSION must be defined (planning/CMakeLists.txt)"
#endif

namespace fs = std::filesystem;

namespace caps::planning {
namespace {

using json = nlohmann::json;

const char* const formatName = "caps-plan";
const char* const operationKinds = "place, move, offset, set-parameter, undermine, clear-undermining, draw";

template <class... F> struct Overloaded : F...
{
  using F::operator()...;
};

std::string operationLabel(int number, const std::string& what)
{
  return "operation " + std::to_string(number) + " (" + what + ")";
}

/// @name Reading fields of one operation; RecipeError names the operation and field
///@{
struct OperationReader
{
  const json& j;
  int number;
  std::string kind;

  [[noreturn]] void fail(const std::string& what) const
  {
    throw RecipeError(number, operationLabel(number, kind) + ": " + what);
  }
  const json& field(const char* key) const
  {
    const auto it = j.find(key);
    if (it == j.end() || it->is_null())
      fail(std::string("\"") + key + "\" is missing");
    return *it;
  }
  double finite(const json& v, const std::string& what) const
  {
    if (!v.is_number() || !std::isfinite(v.get<double>()))
      fail(what + " must be a finite number, not " + v.dump());
    return v.get<double>();
  }
  double real(const char* key) const { return finite(field(key), std::string("\"") + key + "\""); }
  int whole(const char* key) const
  {
    const json& v = field(key);
    if (!v.is_number_integer() || v.get<long long>() < 0 || v.get<long long>() > 1000000)
      fail(std::string("\"") + key + "\" must be a whole number from 0, not " + v.dump());
    return int(v.get<long long>());
  }
  std::string text(const char* key) const
  {
    const json& v = field(key);
    if (!v.is_string() || v.get<std::string>().empty())
      fail(std::string("\"") + key + "\" must be a non-empty string, not " + v.dump());
    return v.get<std::string>();
  }
  Eigen::Vector2d pair(const char* key) const
  {
    const json& v = field(key);
    if (!v.is_array() || v.size() != 2)
      fail(std::string("\"") + key + "\" must be two numbers [a, b], not " + v.dump());
    const std::string what = std::string("\"") + key + "\"";
    return {finite(v[0], what), finite(v[1], what)};
  }
  std::vector<Eigen::Vector2d> pairs(const char* key) const
  {
    const json& v = field(key);
    const std::string what = std::string("\"") + key + "\"";
    if (!v.is_array())
      fail(what + " must be a list of points [[a, b], ...], not " + v.dump());
    std::vector<Eigen::Vector2d> points;
    for (std::size_t k = 0; k < v.size(); ++k)
    {
      const json& p = v[k];
      const std::string which = "point " + std::to_string(k) + " of " + what;
      if (!p.is_array() || p.size() != 2)
        fail(which + " must be two numbers [a, b], not " + p.dump());
      points.emplace_back(finite(p[0], which), finite(p[1], which));
    }
    return points;
  }
};
///@}

/// Doubles as their IEEE-754 bits, integers as 64 bits, both little-endian,
/// so the hash is the same on every machine.
class HashInput
{
public:
  HashInput() : sha_(QCryptographicHash::Sha256) {}
  void bytes(const void* data, std::size_t size)
  {
    const char* p = static_cast<const char*>(data);
    while (size > 0) // addData takes an int length
    {
      const std::size_t chunk = std::min<std::size_t>(size, std::size_t(1) << 30);
      sha_.addData(p, int(chunk));
      p += chunk;
      size -= chunk;
    }
  }
  void integer(std::int64_t v) { little(std::uint64_t(v)); }
  void real(double v) { little(std::bit_cast<std::uint64_t>(v)); }
  void text(const std::string& s)
  {
    integer(std::int64_t(s.size()));
    bytes(s.data(), s.size());
  }
  std::string hex() const { return sha_.result().toHex().toStdString(); }

private:
  void little(std::uint64_t v)
  {
    unsigned char b[8];
    for (int k = 0; k < 8; ++k)
      b[k] = static_cast<unsigned char>(v >> (8 * k));
    bytes(b, 8);
  }
  QCryptographicHash sha_;
};

bool isSha256Hex(const std::string& s)
{
  return s.size() == 64 &&
         std::all_of(s.begin(), s.end(), [](char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); });
}

IncisionPlan checked(IncisionPlan plan, const seg::RangeMap& skin)
{
  checkPlan(plan, skin);
  return plan;
}

} // namespace

std::string describe(const PlanOperation& operation)
{
  return std::visit(
    Overloaded{
      [](const PlaceProcedure& o) { return "place " + o.procedure; },
      [](const MoveCutPoint& o) { return "move cut point " + std::to_string(o.point); },
      [](const OffsetBorderPoint& o) { return "offset border point " + std::to_string(o.vertex); },
      [](const SetParameter& o) { return "set parameter " + o.name; },
      [](const UndermineRegion& o) { return "undermine a region of " + std::to_string(o.region.size()) + " points"; },
      [](const ClearUndermining&) { return std::string("clear undermining"); },
      [](const DrawCut& o) { return "draw a cut of " + std::to_string(o.points.size()) + " points"; },
    },
    operation);
}

std::vector<SutureEdges> straightClosureSutures(int pathPoints)
{
  const int n = pathPoints;
  const auto twin = [n](int i) { return i == 0 || i == n - 1 ? i : 2 * n - 2 - i; };
  std::vector<SutureEdges> sutures;
  for (int i = 0; i + 1 < n; ++i)
    sutures.push_back({{i, i + 1}, {twin(i), twin(i + 1)}});
  return sutures;
}

const ProcedureTemplate& findProcedure(const ProcedureLibrary& library, const std::string& id)
{
  if (const ProcedureTemplate* t = library.find(id))
    return *t;
  std::string known;
  for (const auto& t : library.procedures())
    known += (known.empty() ? "" : ", ") + t.id();
  std::string message =
    "there is no procedure '" + id + "' (" +
    (known.empty() ? std::string("the procedures folder has none that can be used") : "there are: " + known) + ")";
  if (!library.errors().empty())
  {
    // A file that fails validation is left out: say so, or the surgeon
    // looks for a typo in a name that is right.
    message += "; procedure files left out because they are wrong:";
    for (const auto& e : library.errors())
      message += "\n  " + e;
    message += "\nfix the file or choose one of the procedures there are";
  }
  throw std::invalid_argument(message);
}

IncisionPlan applyOperation(const IncisionPlan& plan, const PlanOperation& operation, int number,
                            const seg::RangeMap& skin, const ProcedureLibrary& library)
{
  const std::string label = operationLabel(number, describe(operation));
  const auto needCut = [&]() {
    if (plan.pointCount() == 0)
      throw RecipeError(number, label + ": there is no cut yet; a plan starts by placing a procedure or drawing a cut");
  };
  const auto needFinite = [&](const Eigen::Vector2d& v, const char* what) {
    if (!v.allFinite())
      throw RecipeError(number, label + ": the " + std::string(what) + " is not a number");
  };
  try
  {
    return std::visit(
      Overloaded{
        [&](const PlaceProcedure& o) {
          if (!std::isfinite(o.at.theta) || !std::isfinite(o.at.z))
            throw RecipeError(number, label + ": the centre is not a number");
          return findProcedure(library, o.procedure).place(skin, o.at, o.values);
        },
        [&](const MoveCutPoint& o) {
          needCut();
          needFinite(o.thetaZN, "new position");
          IncisionPlan next = plan;
          next.moveCutPoint(o.point, o.thetaZN);
          return checked(std::move(next), skin);
        },
        [&](const OffsetBorderPoint& o) {
          needCut();
          needFinite(o.offset, "offset");
          IncisionPlan next = plan;
          next.offsetBorderPoint(o.vertex, o.offset);
          return checked(std::move(next), skin);
        },
        [&](const SetParameter& o) {
          needCut();
          if (plan.procedure().empty())
            throw RecipeError(number, label + ": the cut was drawn by hand, not placed from a procedure; "
                                              "it has no parameters to change");
          if (!std::isfinite(o.value))
            throw RecipeError(number, label + ": the value is not a number");
          std::map<std::string, double> values = plan.parameters();
          values[o.name] = o.value; // an unknown name: place() lists the parameters there are
          IncisionPlan next = findProcedure(library, plan.procedure()).place(skin, plan.centre(), values);
          // The skin the surgeon freed is not part of the cut the template draws: it stays.
          for (const UnderminedRegion& region : plan.underminedRegions())
            next.addUnderminedRegion(region);
          return next;
        },
        [&](const UndermineRegion& o) {
          needCut();
          checkUnderminedRegion(o.region, plan.chart(skin));
          IncisionPlan next = plan;
          next.addUnderminedRegion(o.region);
          return next;
        },
        [&](const DrawCut& o) {
          if (o.points.size() < 2)
            throw RecipeError(number, label + ": a cut needs at least 2 points");
          for (const Eigen::Vector2d& p : o.points)
            needFinite(p, "point");
          // The chart's centre: the middle of the points, θ unwrapped about
          // the first so a cut across the back of the head stays one piece.
          const seg::CylindricalFrame& frame = skin.frame();
          const seg::CylindricalPoint first = frame.fromNormalized({1.0, o.points[0].x(), o.points[0].y()});
          double theta = 0.0, z = 0.0;
          for (const Eigen::Vector2d& p : o.points)
          {
            const seg::CylindricalPoint c = frame.fromNormalized({1.0, p.x(), p.y()});
            theta += first.theta + seg::CylindricalFrame::wrapTheta(c.theta - first.theta);
            z += c.z;
          }
          const double count = double(o.points.size());
          IncisionPlan next(o.points, {seg::CylindricalFrame::wrapTheta(theta / count), z / count});
          std::vector<SutureEdges> sewnBack = straightClosureSutures(int(o.points.size()));
          const std::size_t sutureCount = sewnBack.size();
          next.setSutures(std::move(sewnBack), std::vector<std::string>(sutureCount, "the cut"));
          return checked(std::move(next), skin);
        },
        [&](const ClearUndermining&) {
          needCut();
          IncisionPlan next = plan;
          next.clearUnderminedRegions();
          return next;
        },
      },
      operation);
  }
  catch (const RecipeError&)
  {
    throw;
  }
  catch (const std::exception& e)
  {
    throw RecipeError(number, label + ": " + e.what());
  }
}

IncisionPlan applyRecipe(const PlanRecipe& recipe, const seg::RangeMap& skin, const ProcedureLibrary& library)
{
  if (recipe.operations.empty())
    throw RecipeError(0, "the plan has no operations; it must start by placing a procedure");
  IncisionPlan plan;
  for (std::size_t k = 0; k < recipe.operations.size(); ++k)
    plan = applyOperation(plan, recipe.operations[k], int(k + 1), skin, library);
  return plan;
}

RecordedPlan::RecordedPlan(std::string ctSha256)
{
  recipe_.ctSha256 = std::move(ctSha256);
  recipe_.softwareVersion = softwareVersion();
}

void RecordedPlan::apply(const PlanOperation& operation, const seg::RangeMap& skin, const ProcedureLibrary& library)
{
  IncisionPlan next = applyOperation(plan_, operation, int(recipe_.operations.size() + 1), skin, library);
  recipe_.operations.push_back(operation); // may throw bad_alloc: nothing changed yet
  plan_ = std::move(next);
}

json operationToJson(const PlanOperation& operation)
{
  return std::visit(
    Overloaded{
      [](const PlaceProcedure& o) {
        return json{{"operation", "place"},
                    {"procedure", o.procedure},
                    {"theta", o.at.theta},
                    {"z", o.at.z},
                    {"values", o.values}};
      },
      [](const MoveCutPoint& o) {
        return json{{"operation", "move"}, {"point", o.point}, {"thetaZN", {o.thetaZN.x(), o.thetaZN.y()}}};
      },
      [](const OffsetBorderPoint& o) {
        return json{{"operation", "offset"}, {"vertex", o.vertex}, {"offset", {o.offset.x(), o.offset.y()}}};
      },
      [](const SetParameter& o) {
        return json{{"operation", "set-parameter"}, {"name", o.name}, {"value", o.value}};
      },
      [](const UndermineRegion& o) {
        json points = json::array();
        for (const auto& p : o.region)
          points.push_back({p.x(), p.y()});
        return json{{"operation", "undermine"}, {"region", std::move(points)}};
      },
      [](const ClearUndermining&) {
        return json{{"operation", "clear-undermining"}};
      },
      [](const DrawCut& o) {
        json points = json::array();
        for (const auto& p : o.points)
          points.push_back({p.x(), p.y()});
        return json{{"operation", "draw"}, {"points", std::move(points)}};
      },
    },
    operation);
}

PlanOperation operationFromJson(const json& j, int number)
{
  if (!j.is_object())
    throw RecipeError(number, "operation " + std::to_string(number) +
                                " must be an object like {\"operation\": \"move\", ...}, not " + j.dump());
  const auto kindIt = j.find("operation");
  if (kindIt == j.end() || !kindIt->is_string())
    throw RecipeError(number, "operation " + std::to_string(number) +
                                " does not say which operation it is: give \"operation\": one of " + operationKinds);
  OperationReader r{j, number, kindIt->get<std::string>()};
  if (r.kind == "place")
  {
    PlaceProcedure o;
    o.procedure = r.text("procedure");
    o.at = {r.real("theta"), r.real("z")};
    const json& values = r.field("values");
    if (!values.is_object())
      r.fail("\"values\" must be an object of parameter names and numbers, not " + values.dump());
    for (const auto& [name, value] : values.items())
      o.values[name] = r.finite(value, "parameter \"" + name + "\"");
    return o;
  }
  if (r.kind == "move")
    return MoveCutPoint{r.whole("point"), r.pair("thetaZN")};
  if (r.kind == "offset")
    return OffsetBorderPoint{r.whole("vertex"), r.pair("offset")};
  if (r.kind == "set-parameter")
    return SetParameter{r.text("name"), r.real("value")};
  if (r.kind == "undermine")
    return UndermineRegion{r.pairs("region")};
  if (r.kind == "clear-undermining")
    return ClearUndermining{};
  if (r.kind == "draw")
    return DrawCut{r.pairs("points")};
  throw RecipeError(number, "operation " + std::to_string(number) + " is '" + r.kind +
                              "', which this CAPS does not know; the operations are " + operationKinds +
                              " (a newer CAPS may have written the file)");
}

namespace {

json predictionCheckToJson(const PredictionCheck& c)
{
  // JSON has no NaN: a stretch left out (every point inverted) is null.
  const auto number = [](double x) { return std::isfinite(x) ? json(x) : json(nullptr); };
  const auto xyz = [](const Eigen::Vector3d& p) { return json::array({p.x(), p.y(), p.z()}); };
  return {{"model", tissueModelId(c.model)},
          {"converged", c.converged},
          {"closureFraction", c.closureFraction},
          {"increments", c.increments},
          {"iterations", c.iterations},
          {"dampedIncrements", c.dampedIncrements},
          {"dissipatedFraction", c.dissipatedFraction},
          {"loosePathStoppedAt", c.loosePathStoppedAt},
          {"minDetF", number(c.deformation.minDetF)},
          {"minDetFElement", c.deformation.minDetFElement},
          {"maxStretch", number(c.deformation.maxStretch)},
          {"minStretch", number(c.deformation.minStretch)},
          {"invertedElements", c.deformation.invertedElements},
          {"skinTrianglesChecked", c.skinCrossings.triangles},
          {"skinCrossings", c.skinCrossings.crossingPairs},
          {"tissueCrossings", c.tissueCrossings.crossingPairs},
          {"deepestTissueCrossing", c.tissueCrossings.deepest},
          {"caveat", c.caveat},
          {"meshElements", c.mesh.elements},
          {"meshMinScaledJacobian", c.mesh.minScaledJacobian},
          {"meshMaxEdgeRatio", c.mesh.maxEdgeRatio},
          {"meshElementsBelowScaledJacobianLimit", c.mesh.poorJacobian},
          {"meshElementsAboveEdgeRatioLimit", c.mesh.poorEdgeRatio},
          {"meshElementsOutsideLimits", c.mesh.poorElements},
          {"meshWorstScaledJacobianAt", xyz(c.mesh.worstJacobianAt)},
          {"meshWorstEdgeRatioAt", xyz(c.mesh.worstEdgeRatioAt)},
          {"meshNodesMoved", c.nodeOptimization.movedNodes},
          {"meshLargestNodeMove", c.nodeOptimization.largestMove},
          {"meshMinScaledJacobianAsPlaced", c.nodeOptimization.minScaledJacobianBefore},
          {"meshElementsBelowScaledJacobianLimitAsPlaced", c.nodeOptimization.poorElementsBefore},
          {"admissible", c.admissible()},
          {"problem", c.problem}};
}

PredictionCheck predictionCheckFromJson(const json& j)
{
  const auto bad = [](const std::string& what) { throw RecipeError(0, "\"prediction\": " + what); };
  if (!j.is_object())
    bad("must be an object (the check of the prediction caps plan made), not " + j.dump().substr(0, 80));
  PredictionCheck c;
  const auto model = j.find("model");
  const auto known =
    model != j.end() && model->is_string() ? tissueModelFromId(model->get<std::string>()) : std::nullopt;
  if (!known)
    bad("\"model\" must be \"linear\" or \"large-deformation\"");
  c.model = *known;
  const auto number = [&](const char* key, double fallback) {
    const auto it = j.find(key);
    if (it == j.end() || it->is_null())
      return fallback;
    if (!it->is_number())
      bad(std::string("\"") + key + "\" must be a number, not " + it->dump());
    return it->get<double>();
  };
  const auto point = [&](const char* key) {
    const auto it = j.find(key);
    if (it == j.end() || it->is_null())
      return Eigen::Vector3d(Eigen::Vector3d::Zero());
    if (!it->is_array() || it->size() != 3 ||
        !std::all_of(it->begin(), it->end(), [](const json& x) { return x.is_number(); }))
      bad(std::string("\"") + key + "\" must be [x, y, z] in mm, not " + it->dump());
    return Eigen::Vector3d((*it)[0].get<double>(), (*it)[1].get<double>(), (*it)[2].get<double>());
  };
  if (const auto converged = j.find("converged"); converged != j.end())
  {
    if (!converged->is_boolean())
      bad("\"converged\" must be true or false, not " + converged->dump());
    c.converged = converged->get<bool>();
  }
  c.closureFraction = number("closureFraction", 1.0);
  c.increments = int(number("increments", 0));
  c.iterations = int(number("iterations", 0));
  c.dampedIncrements = int(number("dampedIncrements", 0));
  c.dissipatedFraction = number("dissipatedFraction", 0.0);
  c.loosePathStoppedAt = number("loosePathStoppedAt", -1.0);
  c.deformation.minDetF = number("minDetF", std::numeric_limits<double>::quiet_NaN());
  c.deformation.minDetFElement = int(number("minDetFElement", -1));
  c.deformation.maxStretch = number("maxStretch", std::numeric_limits<double>::quiet_NaN());
  c.deformation.minStretch = number("minStretch", std::numeric_limits<double>::quiet_NaN());
  c.deformation.invertedElements = int(number("invertedElements", 0));
  c.skinCrossings.triangles = int(number("skinTrianglesChecked", 0));
  c.skinCrossings.crossingPairs = int(number("skinCrossings", 0));
  c.tissueCrossings.crossingPairs = int(number("tissueCrossings", 0));
  c.tissueCrossings.deepest = number("deepestTissueCrossing", 0.0);
  if (const auto caveat = j.find("caveat"); caveat != j.end() && caveat->is_string())
    c.caveat = caveat->get<std::string>();
  c.mesh.elements = int(number("meshElements", 0));
  c.mesh.minScaledJacobian = number("meshMinScaledJacobian", 1.0);
  c.mesh.maxEdgeRatio = number("meshMaxEdgeRatio", 1.0);
  c.mesh.poorJacobian = int(number("meshElementsBelowScaledJacobianLimit", 0));
  c.mesh.poorEdgeRatio = int(number("meshElementsAboveEdgeRatioLimit", 0));
  c.mesh.poorElements =
    int(number("meshElementsOutsideLimits", double(std::max(c.mesh.poorJacobian, c.mesh.poorEdgeRatio))));
  c.mesh.worstJacobianAt = point("meshWorstScaledJacobianAt");
  c.mesh.worstEdgeRatioAt = point("meshWorstEdgeRatioAt");
  c.nodeOptimization.movedNodes = int(number("meshNodesMoved", 0));
  c.nodeOptimization.largestMove = number("meshLargestNodeMove", 0.0);
  c.nodeOptimization.minScaledJacobianBefore = number("meshMinScaledJacobianAsPlaced", c.mesh.minScaledJacobian);
  c.nodeOptimization.poorElementsBefore =
    int(number("meshElementsBelowScaledJacobianLimitAsPlaced", double(c.mesh.poorJacobian)));
  if (const auto problem = j.find("problem"); problem != j.end() && problem->is_string())
    c.problem = problem->get<std::string>();
  return c;
}

/// "closure": {"force": N, "largestSuture": N, "peakWoundStress": MPa,
/// "meanWoundStress": MPa, "woundRadius": mm}, every one a number >= 0.
ClosureRecord closureRecordFromJson(const json& j)
{
  const auto bad = [](const std::string& what) { throw RecipeError(0, "\"closure\": " + what); };
  if (!j.is_object())
    bad("must be an object (the closure numbers of the prediction), not " + j.dump().substr(0, 80));
  const auto number = [&](const char* key) {
    const auto it = j.find(key);
    if (it == j.end() || !it->is_number() || !(it->get<double>() >= 0.0) || !std::isfinite(it->get<double>()))
      bad(std::string("\"") + key + "\" must be a number of 0 or more, not " +
          (it == j.end() ? "missing" : it->dump()));
    return it->get<double>();
  };
  ClosureRecord c;
  c.force = number("force");
  c.largestSuture = number("largestSuture");
  c.peakWoundStress = number("peakWoundStress");
  c.meanWoundStress = number("meanWoundStress");
  c.woundRadius = number("woundRadius");
  // The tension came later: absent in older files.
  if (j.contains("tensionPerCentimetre"))
  {
    c.tensionPerCentimetre = number("tensionPerCentimetre");
    c.peakTensionPerCentimetre = number("peakTensionPerCentimetre");
    c.peakForcePerStitch = number("peakForcePerStitch");
    c.stitchSpacing = number("stitchSpacing");
    if (const auto line = j.find("peakTensionLine"); line != j.end() && line->is_string())
      c.peakTensionLine = line->get<std::string>();
  }
  return c;
}

} // namespace

namespace {

/// {"alongLines": N/mm, "acrossLines": N/mm}, each in [0, 1].
std::array<double, 2> preTensionFromJson(const json& j)
{
  std::array<double, 2> t{};
  const char* names[2] = {"alongLines", "acrossLines"};
  for (int k = 0; k < 2; ++k)
  {
    const auto it = j.is_object() ? j.find(names[k]) : j.end();
    if (it == j.end() || !it->is_number() || !(it->get<double>() >= 0.0) || !(it->get<double>() <= 1.0))
      throw RecipeError(0, "\"preTension\" in \"simulation\" must be {\"alongLines\": N/mm, \"acrossLines\": N/mm}, "
                           "each from 0 to 1, not " +
                             j.dump());
    t[std::size_t(k)] = it->get<double>();
  }
  return t;
}

} // namespace

json recipeToJson(const PlanRecipe& recipe)
{
  json operations = json::array();
  for (const auto& o : recipe.operations)
    operations.push_back(operationToJson(o));
  json j{{"format", formatName},
         {"formatVersion", recipeFormatVersion},
         {"softwareVersion", recipe.softwareVersion},
         {"ctSha256", recipe.ctSha256},
         {"operations", std::move(operations)}};
  if (recipe.elementSize > 0.0)
    j["simulation"] = {{"elementSize", recipe.elementSize}};
  if (recipe.elementSize > 0.0 && recipe.cutLayers)
    j["simulation"]["cutLayers"] = *recipe.cutLayers;
  if (recipe.elementSize > 0.0 && recipe.model != TissueModel::LinearElastic)
    j["simulation"]["model"] = tissueModelId(recipe.model);
  if (recipe.elementSize > 0.0 && recipe.underminingWidth)
    j["simulation"]["underminingWidth"] = *recipe.underminingWidth;
  if (recipe.elementSize > 0.0 && recipe.preTension)
    j["simulation"]["preTension"] = {{"alongLines", (*recipe.preTension)[0]}, {"acrossLines", (*recipe.preTension)[1]}};
  if (recipe.prediction)
    j["prediction"] = predictionCheckToJson(*recipe.prediction);
  if (recipe.closure)
    j["closure"] = {{"force", recipe.closure->force},
                    {"largestSuture", recipe.closure->largestSuture},
                    {"peakWoundStress", recipe.closure->peakWoundStress},
                    {"meanWoundStress", recipe.closure->meanWoundStress},
                    {"woundRadius", recipe.closure->woundRadius},
                    {"tensionPerCentimetre", recipe.closure->tensionPerCentimetre},
                    {"peakTensionPerCentimetre", recipe.closure->peakTensionPerCentimetre},
                    {"peakForcePerStitch", recipe.closure->peakForcePerStitch},
                    {"stitchSpacing", recipe.closure->stitchSpacing},
                    {"peakTensionLine", recipe.closure->peakTensionLine}};
  return j;
}

PlanRecipe recipeFromJson(const json& j)
{
  const auto bad = [](const std::string& what) { throw RecipeError(0, what); };
  if (!j.is_object())
    bad("a plan file is a JSON object with \"format\": \"caps-plan\" and \"operations\", not " +
        j.dump().substr(0, 80));
  if (!j.contains("format") || j["format"] != formatName)
    bad("this is not a CAPS plan: \"format\" must be \"caps-plan\" (caps plan writes it as plan.json)");
  const auto version = j.find("formatVersion");
  if (version == j.end() || !version->is_number_integer() || version->get<long long>() < 1)
    bad("\"formatVersion\" must be a whole number from 1");
  if (version->get<long long>() > recipeFormatVersion)
    bad("the plan was written in plan format " + version->dump() + " by a newer CAPS; this one reads format " +
        std::to_string(recipeFormatVersion) + ": update CAPS to replay it");
  PlanRecipe recipe;
  for (const auto& [key, out] :
       {std::pair{"softwareVersion", &recipe.softwareVersion}, std::pair{"ctSha256", &recipe.ctSha256}})
    if (const auto it = j.find(key); it != j.end() && !it->is_null())
    {
      if (!it->is_string())
        bad(std::string("\"") + key + "\" must be a string, not " + it->dump());
      *out = it->get<std::string>();
    }
  if (!recipe.ctSha256.empty() && !isSha256Hex(recipe.ctSha256))
    bad("\"ctSha256\" must be 64 lowercase hex digits (the SHA-256 of the CT), not \"" + recipe.ctSha256 + "\"");
  const auto operations = j.find("operations");
  if (operations == j.end() || !operations->is_array())
    bad("\"operations\" must be a list of operations");
  for (std::size_t k = 0; k < operations->size(); ++k)
    recipe.operations.push_back(operationFromJson((*operations)[k], int(k + 1)));
  if (const auto simulation = j.find("simulation"); simulation != j.end() && !simulation->is_null())
  {
    const auto size = simulation->is_object() ? simulation->find("elementSize") : simulation->end();
    if (size == simulation->end() || !size->is_number() || !(size->get<double>() > 0.0) ||
        !std::isfinite(size->get<double>()))
      bad("\"simulation\" must be {\"elementSize\": MM} with a positive size, not " + simulation->dump());
    recipe.elementSize = size->get<double>();
    if (const auto cut = simulation->find("cutLayers"); cut != simulation->end())
    {
      if (!cut->is_number_integer() || cut->get<long long>() < 0 || cut->get<long long>() > 16)
        bad("\"cutLayers\" in \"simulation\" must be the number of tissue layers cut (0 for full thickness), not " +
            cut->dump());
      recipe.cutLayers = int(cut->get<long long>());
    }
    if (const auto model = simulation->find("model"); model != simulation->end())
    {
      const auto known = model->is_string() ? tissueModelFromId(model->get<std::string>()) : std::nullopt;
      if (!known)
        bad("\"model\" in \"simulation\" must be \"linear\" or \"large-deformation\", not " + model->dump());
      recipe.model = *known;
    }
    if (const auto width = simulation->find("underminingWidth"); width != simulation->end())
    {
      if (!width->is_number() || !(width->get<double>() >= 0.0) || !(width->get<double>() <= 100.0))
        bad("\"underminingWidth\" in \"simulation\" must be the undermining band in mm (0 to 100), not " +
            width->dump());
      recipe.underminingWidth = width->get<double>();
    }
    if (const auto tension = simulation->find("preTension"); tension != simulation->end())
      recipe.preTension = preTensionFromJson(*tension);
  }
  if (const auto prediction = j.find("prediction"); prediction != j.end() && !prediction->is_null())
    recipe.prediction = predictionCheckFromJson(*prediction);
  if (const auto closure = j.find("closure"); closure != j.end() && !closure->is_null())
    recipe.closure = closureRecordFromJson(*closure);
  return recipe;
}

ClosureRecord closureRecordOf(const PlanPrediction& prediction, const WoundStress& wound, const WoundTension& tension)
{
  ClosureRecord c;
  c.force = prediction.closure.magnitudeSum;
  c.largestSuture = prediction.closure.largest;
  c.peakWoundStress = wound.peakVonMises;
  c.meanWoundStress = wound.meanVonMises;
  c.woundRadius = wound.radius;
  double across = 0.0, length = 0.0;
  for (const WoundLineTension& l : tension.lines)
  {
    across += l.acrossForce;
    length += l.length;
  }
  c.tensionPerCentimetre = length > 0.0 ? 10.0 * across / length : 0.0;
  c.peakTensionPerCentimetre = tension.peakPerCentimetre;
  c.peakForcePerStitch = tension.peakPerStitch;
  c.stitchSpacing = tension.stitchSpacing;
  c.peakTensionLine = tension.peakLine;
  return c;
}

void writeRecipe(const PlanRecipe& recipe, const fs::path& file)
{
  const fs::path beside = file.string() + ".writing";
  {
    std::ofstream out(beside, std::ios::binary | std::ios::trunc);
    out << recipeToJson(recipe).dump(2) << "\n";
    if (!out)
      throw std::runtime_error("cannot write " + beside.string() + ": check the folder's permissions and space");
  }
  std::error_code ec;
  fs::rename(beside, file, ec);
  if (ec)
    throw std::runtime_error("cannot write " + file.string() + ": " + ec.message());
}

PlanRecipe readRecipe(const fs::path& file)
{
  std::ifstream in(file, std::ios::binary);
  if (!in)
    throw RecipeError(0, "cannot read the plan file " + file.string() +
                           ": check the path (caps plan writes "
                           "DIR/plan.json)");
  json j;
  try
  {
    j = json::parse(in);
  }
  catch (const json::parse_error& e)
  {
    throw RecipeError(0, file.string() + " is not a plan file: it is not JSON (" + e.what() +
                           "); give the plan.json that caps plan wrote");
  }
  try
  {
    return recipeFromJson(j);
  }
  catch (const RecipeError& e)
  {
    throw RecipeError(e.operation(), file.string() + ": " + e.what());
  }
}

std::string ctContentHash(vtkImageData* image)
{
  vtkDataArray* scalars = image && image->GetPointData() ? image->GetPointData()->GetScalars() : nullptr;
  if (!scalars || image->GetNumberOfPoints() == 0)
    throw std::invalid_argument("the CT has no voxels to fingerprint: read it again");
  HashInput h;
  h.text("CAPS CT content 1"); // the layout of what follows; change it with the layout
  int dims[3], extent[6];
  image->GetDimensions(dims);
  image->GetExtent(extent);
  for (int k = 0; k < 3; ++k)
    h.integer(dims[k]);
  for (int k = 0; k < 3; ++k)
    h.integer(extent[2 * k]);
  for (const double* v : {image->GetSpacing(), image->GetOrigin()})
    for (int k = 0; k < 3; ++k)
      h.real(v[k]);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      h.real(image->GetDirectionMatrix()->GetElement(r, c));
  h.text(scalars->GetDataTypeAsString());
  h.integer(scalars->GetNumberOfComponents());
  const std::size_t size = std::size_t(scalars->GetDataTypeSize());
  const std::size_t count = std::size_t(scalars->GetNumberOfTuples()) * std::size_t(scalars->GetNumberOfComponents());
  h.integer(std::int64_t(count));
  const auto* voxels = static_cast<const unsigned char*>(scalars->GetVoidPointer(0));
  if constexpr (std::endian::native == std::endian::little)
    h.bytes(voxels, size * count);
  else
  {
    std::vector<unsigned char> swapped(size * std::min<std::size_t>(count, 1 << 20));
    for (std::size_t first = 0; first < count; first += swapped.size() / size)
    {
      const std::size_t n = std::min(count - first, swapped.size() / size);
      for (std::size_t i = 0; i < n; ++i)
        std::reverse_copy(voxels + (first + i) * size, voxels + (first + i + 1) * size, swapped.data() + i * size);
      h.bytes(swapped.data(), n * size);
    }
  }
  return h.hex();
}

std::string softwareVersion()
{
  return CAPS_VERSION;
}

} // namespace caps::planning
