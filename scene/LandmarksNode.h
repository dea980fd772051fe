#pragma once

#include <array>
#include <string>
#include <vector>

#include "scene/Node.h"

namespace caps {

/// @brief Named points on the patient (nasion, pogonion, the corner of the
/// mouth...) placed by the surgeon while reviewing the tissue thickness;
/// the muscle sets (planning/MuscleSet.h) are placed relative to them. And
/// the distances measured on the slices (the ruler). Small fields only.
class LandmarksNode : public Node
{
public:
  struct Landmark
  {
    std::string name;
    std::array<double, 3> position{}; ///< patient LPS, mm
    bool operator==(const Landmark&) const = default;
  };

  /// A straight distance measured between two points (a ruler on a slice).
  struct Distance
  {
    std::string name;
    std::array<double, 3> from{}; ///< patient LPS, mm
    std::array<double, 3> to{};   ///< patient LPS, mm
    double length() const;        ///< mm
    bool operator==(const Distance&) const = default;
  };

  NodeType type() const override { return NodeType::Landmarks; }

  const std::vector<Landmark>& landmarks() const { return landmarks_; }
  void setLandmarks(std::vector<Landmark> landmarks);
  void add(Landmark landmark);
  /// Removes landmark @a index; nothing if there is none.
  void remove(std::size_t index);

  const std::vector<Distance>& distances() const { return distances_; }
  void addDistance(Distance distance);
  /// Removes distance @a index; nothing if there is none.
  void removeDistance(std::size_t index);

protected:
  void writeFields(nlohmann::json& j) const override;
  void readFields(const nlohmann::json& j) override;

private:
  std::vector<Landmark> landmarks_;
  std::vector<Distance> distances_;
};

} // namespace caps
