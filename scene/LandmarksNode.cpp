#include "scene/LandmarksNode.h"

#include <cmath>

#include "scene/JsonFields.h"
#include "scene/SceneError.h"

namespace caps {

void LandmarksNode::setLandmarks(std::vector<Landmark> landmarks)
{
  landmarks_ = std::move(landmarks);
  modified();
}

void LandmarksNode::add(Landmark landmark)
{
  landmarks_.push_back(std::move(landmark));
  modified();
}

void LandmarksNode::remove(std::size_t index)
{
  if (index >= landmarks_.size())
    return;
  landmarks_.erase(landmarks_.begin() + static_cast<std::ptrdiff_t>(index));
  modified();
}

double LandmarksNode::Distance::length() const
{
  return std::hypot(to[0] - from[0], to[1] - from[1], to[2] - from[2]);
}

void LandmarksNode::addDistance(Distance distance)
{
  distances_.push_back(std::move(distance));
  modified();
}

void LandmarksNode::removeDistance(std::size_t index)
{
  if (index >= distances_.size())
    return;
  distances_.erase(distances_.begin() + static_cast<std::ptrdiff_t>(index));
  modified();
}

namespace {

void requireFinite(const std::array<double, 3>& p, const std::string& what)
{
  for (double c : p)
    if (!std::isfinite(c))
      throw SceneError(what + " has a position that is not a number");
}

} // namespace

void LandmarksNode::writeFields(nlohmann::json& j) const
{
  nlohmann::json list = nlohmann::json::array();
  for (const auto& l : landmarks_)
    list.push_back({{"name", l.name}, {"position", l.position}});
  j["landmarks"] = list;
  nlohmann::json distances = nlohmann::json::array();
  for (const auto& d : distances_)
    distances.push_back({{"name", d.name}, {"from", d.from}, {"to", d.to}});
  j["distances"] = distances;
}

void LandmarksNode::readFields(const nlohmann::json& j)
{
  // A list that is absent or null stays as it is (JsonFields.h); scenes
  // saved before the ruler have no distances.
  if (auto it = j.find("landmarks"); it != j.end() && !it->is_null())
  {
    std::vector<Landmark> read;
    for (const auto& entry : jsonfields::list(*it, "landmarks of '" + name() + "'"))
    {
      Landmark l;
      jsonfields::read(entry, "name", l.name);
      jsonfields::read(entry, "position", l.position);
      requireFinite(l.position, "landmark '" + l.name + "' of '" + name() + "'");
      read.push_back(std::move(l));
    }
    landmarks_ = std::move(read);
  }
  if (auto it = j.find("distances"); it != j.end() && !it->is_null())
  {
    std::vector<Distance> read;
    for (const auto& entry : jsonfields::list(*it, "distances of '" + name() + "'"))
    {
      Distance d;
      jsonfields::read(entry, "name", d.name);
      jsonfields::read(entry, "from", d.from);
      jsonfields::read(entry, "to", d.to);
      requireFinite(d.from, "distance '" + d.name + "' of '" + name() + "'");
      requireFinite(d.to, "distance '" + d.name + "' of '" + name() + "'");
      read.push_back(std::move(d));
    }
    distances_ = std::move(read);
  }
}

} // namespace caps
