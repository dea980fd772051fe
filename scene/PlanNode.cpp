#include "scene/PlanNode.h"

#include <cmath>
#include <utility>

#include "scene/JsonFields.h"
#include "scene/SceneError.h"

namespace caps {

void PlanNode::setProcedure(std::string procedure)
{
  procedure_ = std::move(procedure);
  modified();
}

void PlanNode::setParameters(std::map<std::string, double> parameters)
{
  parameters_ = std::move(parameters);
  modified();
}

void PlanNode::setParameter(const std::string& key, double value)
{
  parameters_[key] = value;
  modified();
}

void PlanNode::setCutPath(std::vector<Eigen::Vector2d> path)
{
  cutPath_ = std::move(path);
  modified();
}

void PlanNode::setCutPoint(std::size_t index, const Eigen::Vector2d& p)
{
  if (index >= cutPath_.size())
    throw SceneError("plan '" + name() + "' has " + std::to_string(cutPath_.size()) + " cut points; point " +
                     std::to_string(index) + " does not exist");
  cutPath_[index] = p;
  modified();
}

void PlanNode::setSutures(std::vector<std::array<int, 4>> sutures)
{
  sutures_ = std::move(sutures);
  if (woundLineNames_.size() != sutures_.size())
    woundLineNames_.clear();
  modified();
}

void PlanNode::setWoundLineNames(std::vector<std::string> names)
{
  if (!names.empty() && names.size() != sutures_.size())
    throw SceneError("a plan needs one wound line name per suture or none: " + std::to_string(names.size()) +
                     " names for " + std::to_string(sutures_.size()) + " sutures");
  woundLineNames_ = std::move(names);
  modified();
}

void PlanNode::setGenerator(std::string generator)
{
  generator_ = std::move(generator);
  modified();
}

void PlanNode::setUnderminingBand(double millimetres)
{
  underminingBand_ = millimetres;
  modified();
}

void PlanNode::setCutDepth(std::string depth)
{
  if (depth != "bone" && depth != "fascia")
    throw SceneError("the plan's cut depth must be \"bone\" or \"fascia\", not \"" + depth + "\"");
  cutDepth_ = std::move(depth);
  modified();
}

void PlanNode::setCentre(const Eigen::Vector2d& thetaZ)
{
  centre_ = thetaZ;
  modified();
}

void PlanNode::setBorderOffsets(std::vector<Eigen::Vector2d> offsets)
{
  borderOffsets_ = std::move(offsets);
  modified();
}

void PlanNode::setOperations(nlohmann::json operations)
{
  operations_ = jsonfields::list(operations, "the plan's operations");
  modified();
}

void PlanNode::setCtSha256(std::string hash)
{
  ctSha256_ = std::move(hash);
  modified();
}

void PlanNode::setSoftwareVersion(std::string version)
{
  softwareVersion_ = std::move(version);
  modified();
}

namespace {

/// @a value when it is null or an object; else SceneError naming @a what.
nlohmann::json objectOrNull(nlohmann::json value, const std::string& what)
{
  if (!value.is_null() && !value.is_object())
    throw SceneError("a plan's " + what + " must be an object, not " + value.dump().substr(0, 80));
  return value;
}

} // namespace

void PlanNode::setPredictionCheck(nlohmann::json check)
{
  predictionCheck_ = objectOrNull(std::move(check), "prediction check");
  modified();
}

void PlanNode::setClosure(nlohmann::json closure)
{
  closure_ = objectOrNull(std::move(closure), "closure record");
  modified();
}

void PlanNode::setSimulation(nlohmann::json simulation)
{
  if (!simulation.is_null() && !simulation.is_object())
    throw SceneError("a plan's simulation settings must be an object, not " + simulation.dump());
  simulation_ = std::move(simulation);
  modified();
}

void PlanNode::setNotes(std::string notes)
{
  notes_ = std::move(notes);
  modified();
}

void PlanNode::setRangeMapId(NodeId id)
{
  rangeMapId_ = std::move(id);
  modified();
}

void PlanNode::writeFields(nlohmann::json& j) const
{
  j["procedure"] = procedure_;
  j["parameters"] = parameters_;
  auto& path = j["cutPath"] = nlohmann::json::array();
  for (const auto& p : cutPath_)
    path.push_back({p.x(), p.y()});
  j["sutures"] = sutures_;
  if (!woundLineNames_.empty())
    j["woundLineNames"] = woundLineNames_;
  j["generator"] = generator_;
  if (underminingBand_ > 0.0)
    j["underminingBand"] = underminingBand_;
  if (cutDepth_ != "bone")
    j["cutDepth"] = cutDepth_;
  j["centre"] = {centre_.x(), centre_.y()};
  auto& offsets = j["borderOffsets"] = nlohmann::json::array();
  for (const auto& d : borderOffsets_)
    offsets.push_back({d.x(), d.y()});
  j["operations"] = operations_;
  j["ctSha256"] = ctSha256_;
  j["softwareVersion"] = softwareVersion_;
  if (!simulation_.is_null())
    j["simulation"] = simulation_;
  if (!predictionCheck_.is_null())
    j["prediction"] = predictionCheck_;
  if (!closure_.is_null())
    j["closure"] = closure_;
  j["notes"] = notes_;
  j["rangeMapId"] = rangeMapId_;
}

void PlanNode::readFields(const nlohmann::json& j)
{
  jsonfields::read(j, "procedure", procedure_);
  jsonfields::read(j, "parameters", parameters_);
  const auto readPoints = [&j](const char* key, std::vector<Eigen::Vector2d>& out) {
    if (const auto* points = jsonfields::find(j, key))
    {
      std::vector<Eigen::Vector2d> read;
      for (const auto& p : jsonfields::list(*points, key))
      {
        if (!p.is_array() || p.size() != 2 || !p[0].is_number() || !p[1].is_number())
          throw SceneError(std::string("a point of ") + key + " must be two numbers, not " + p.dump());
        read.emplace_back(p[0].get<double>(), p[1].get<double>());
      }
      out = std::move(read);
    }
  };
  readPoints("cutPath", cutPath_);
  readPoints("borderOffsets", borderOffsets_);
  if (const auto* c = jsonfields::find(j, "centre"))
  {
    if (!c->is_array() || c->size() != 2 || !(*c)[0].is_number() || !(*c)[1].is_number())
      throw SceneError("the plan's centre must be two numbers (theta, z), not " + c->dump());
    centre_ = Eigen::Vector2d((*c)[0].get<double>(), (*c)[1].get<double>());
  }
  jsonfields::read(j, "generator", generator_);
  double band = underminingBand_;
  jsonfields::read(j, "underminingBand", band);
  if (!(band >= 0.0) || !std::isfinite(band))
    throw SceneError("the plan's undermining band must be 0 or a positive number of mm, not " + std::to_string(band));
  underminingBand_ = band;
  std::string depth = cutDepth_;
  jsonfields::read(j, "cutDepth", depth);
  if (depth != "bone" && depth != "fascia")
    throw SceneError("the plan's cut depth must be \"bone\" or \"fascia\", not \"" + depth + "\"");
  cutDepth_ = std::move(depth);
  if (const auto* given = jsonfields::find(j, "sutures"))
  {
    std::vector<std::array<int, 4>> sutures;
    for (const auto& s : jsonfields::list(*given, "sutures"))
    {
      if (jsonfields::list(s, "a suture").size() != 4)
        throw SceneError("a suture must have 4 numbers, not " + s.dump());
      sutures.push_back({jsonfields::toInt(s[0], "a suture"), jsonfields::toInt(s[1], "a suture"),
                         jsonfields::toInt(s[2], "a suture"), jsonfields::toInt(s[3], "a suture")});
    }
    sutures_ = std::move(sutures);
  }
  woundLineNames_.clear();
  if (const auto* given = jsonfields::find(j, "woundLineNames"))
  {
    std::vector<std::string> names;
    for (const auto& name : jsonfields::list(*given, "woundLineNames"))
    {
      if (!name.is_string())
        throw SceneError("a wound line name must be text, not " + name.dump());
      names.push_back(name.get<std::string>());
    }
    if (names.size() != sutures_.size())
      throw SceneError("the plan has " + std::to_string(names.size()) + " wound line names for " +
                       std::to_string(sutures_.size()) + " sutures");
    woundLineNames_ = std::move(names);
  }
  if (const auto* operations = jsonfields::find(j, "operations"))
    operations_ = jsonfields::list(*operations, "the plan's operations");
  jsonfields::read(j, "ctSha256", ctSha256_);
  jsonfields::read(j, "softwareVersion", softwareVersion_);
  if (const auto* simulation = jsonfields::find(j, "simulation"))
  {
    if (!simulation->is_null() && !simulation->is_object())
      throw SceneError("a plan's \"simulation\" must be an object, not " + simulation->dump());
    simulation_ = *simulation;
  }
  if (const auto* check = jsonfields::find(j, "prediction"))
    predictionCheck_ = objectOrNull(*check, "\"prediction\"");
  if (const auto* closure = jsonfields::find(j, "closure"))
    closure_ = objectOrNull(*closure, "\"closure\"");

  jsonfields::read(j, "notes", notes_);
  jsonfields::read(j, "rangeMapId", rangeMapId_);
}

} // namespace caps
