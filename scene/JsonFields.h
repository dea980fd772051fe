#pragma once

// Helpers so each node field is one line in toJson and one in fromJson.
// A missing key leaves the field as it is (older files lack newer fields).

#include <Eigen/Core>
#include <array>
#include <nlohmann/json.hpp>

namespace caps::jsonfields {

template <class T>
void read(const nlohmann::json& j, const char* key, T& out) {
  auto it = j.find(key);
  if (it != j.end() && !it->is_null()) it->get_to(out);
}

inline nlohmann::json toJson(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

inline void read(const nlohmann::json& j, const char* key, Eigen::Vector3d& out) {
  auto it = j.find(key);
  if (it == j.end() || it->is_null()) return;
  const auto a = it->get<std::array<double, 3>>();
  out = Eigen::Vector3d(a[0], a[1], a[2]);
}

}  // namespace caps::jsonfields
