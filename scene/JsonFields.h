#pragma once

// Helpers so each node field is one line in toJson and one in fromJson.
// A missing or null key leaves the field as it is (older files lack newer
// fields). Values of the wrong kind throw SceneError or nlohmann's errors.

#include <Eigen/Core>
#include <array>
#include <climits>
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>

#include "scene/SceneError.h"

namespace caps::jsonfields {

template <class T> void read(const nlohmann::json& j, const char* key, T& out)
{
  auto it = j.find(key);
  if (it != j.end() && !it->is_null())
    it->get_to(out);
}

/// @a v as an int; SceneError naming @a what when it is not a whole number
/// in int's range (nlohmann's get<int>() of 1e20 is undefined behaviour).
inline int toInt(const nlohmann::json& v, const std::string& what)
{
  double d = std::nan("");
  if (v.is_number_unsigned())
    d = static_cast<double>(v.get<std::uint64_t>());
  else if (v.is_number())
    d = v.get<double>();
  if (!(d >= INT_MIN && d <= INT_MAX) || d != std::trunc(d))
    throw SceneError(what + " must be a whole number from " + std::to_string(INT_MIN) + " to " +
                     std::to_string(INT_MAX) + ", not " + v.dump());
  return static_cast<int>(d);
}

/// @a v itself when it is a JSON array; SceneError naming @a what otherwise.
inline const nlohmann::json& list(const nlohmann::json& v, const std::string& what)
{
  if (!v.is_array())
    throw SceneError(what + " must be a list, not " + v.dump());
  return v;
}

/// The value of @a key, or nullptr when it is missing or null (the field keeps its value).
inline const nlohmann::json* find(const nlohmann::json& j, const char* key)
{
  auto it = j.find(key);
  return it == j.end() || it->is_null() ? nullptr : &*it;
}

inline nlohmann::json toJson(const Eigen::Vector3d& v)
{
  return {v.x(), v.y(), v.z()};
}

inline void read(const nlohmann::json& j, const char* key, Eigen::Vector3d& out)
{
  auto it = j.find(key);
  if (it == j.end() || it->is_null())
    return;
  const auto a = it->get<std::array<double, 3>>();
  out = Eigen::Vector3d(a[0], a[1], a[2]);
}

} // namespace caps::jsonfields
