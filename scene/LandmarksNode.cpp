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

void LandmarksNode::writeFields(nlohmann::json& j) const
{
  nlohmann::json list = nlohmann::json::array();
  for (const auto& l : landmarks_)
    list.push_back({{"name", l.name}, {"position", l.position}});
  j["landmarks"] = list;
}

void LandmarksNode::readFields(const nlohmann::json& j)
{
  auto it = j.find("landmarks");
  if (it == j.end() || it->is_null())
    return;
  std::vector<Landmark> read;
  for (const auto& entry : jsonfields::list(*it, "landmarks of '" + name() + "'"))
  {
    Landmark l;
    jsonfields::read(entry, "name", l.name);
    jsonfields::read(entry, "position", l.position);
    for (double c : l.position)
      if (!std::isfinite(c))
        throw SceneError("landmark '" + l.name + "' of '" + name() + "' has a position that is not a number");
    read.push_back(std::move(l));
  }
  landmarks_ = std::move(read);
}

} // namespace caps
