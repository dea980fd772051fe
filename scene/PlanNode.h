#pragma once

#include <Eigen/Core>
#include <array>
#include <map>
#include <string>
#include <vector>

#include "scene/Node.h"

namespace caps {

/// @brief A surgical plan: procedure, its parameters and the cut drawn on the
/// skin. JSON only (no bulk file); edits go through ScopedEdit for undo.
class PlanNode : public Node
{
public:
  NodeType type() const override { return NodeType::Plan; }

  /// "elliptical-excision", "z-plasty", "multiple-z-plasty", ...
  const std::string& procedure() const { return procedure_; }
  void setProcedure(std::string procedure);

  /// Named numbers of the procedure (lengths in mm, angles in radians).
  const std::map<std::string, double>& parameters() const { return parameters_; }
  void setParameters(std::map<std::string, double> parameters);
  void setParameter(const std::string& key, double value);

  /// The incision as points in normalised cylindrical space (θ, z) in [-1, 1].
  const std::vector<Eigen::Vector2d>& cutPath() const { return cutPath_; }
  void setCutPath(std::vector<Eigen::Vector2d> path);
  /// Moves one point; throws SceneError when @a index is out of range.
  void setCutPoint(std::size_t index, const Eigen::Vector2d& p);

  /// Each suture joins two hole-border edges {a0, a1, b0, b1}, as hole-loop
  /// vertex indices (Fig. 4.11: twins of a cut point are different
  /// vertices), written as the thesis and the procedure files write them.
  const std::vector<std::array<int, 4>>& sutures() const { return sutures_; }
  void setSutures(std::vector<std::array<int, 4>> sutures);
  /// Per suture, the wound line it closes in the procedure's words ("the
  /// first limb"), or empty; SceneError when neither empty nor one per suture.
  const std::vector<std::string>& woundLineNames() const { return woundLineNames_; }
  void setWoundLineNames(std::vector<std::string> names);

  /// The cut generator of the procedure ("z", "ellipse", ...); empty for a hand-drawn cut.
  const std::string& generator() const { return generator_; }
  void setGenerator(std::string generator);

  /// The band along the sutured edges the procedure undermines by default
  /// (mm on the skin, 0 for none; scenes saved before procedures stated one
  /// read 0, as they were predicted).
  double underminingBand() const { return underminingBand_; }
  void setUnderminingBand(double millimetres);

  /// How deep the procedure cuts: "bone" (every layer; scenes saved before
  /// procedures stated it read so, as they were predicted) or "fascia".
  const std::string& cutDepth() const { return cutDepth_; }
  void setCutDepth(std::string depth);

  /// Where the plan's skin chart is centred: (θ radians, z mm) on the range map's frame.
  const Eigen::Vector2d& centre() const { return centre_; }
  void setCentre(const Eigen::Vector2d& thetaZ);

  /// Excision offsets (§4.4.4): per hole-loop vertex, its move away from its
  /// twin in the skin chart (mm); empty or all zero for a plain incision.
  const std::vector<Eigen::Vector2d>& borderOffsets() const { return borderOffsets_; }
  void setBorderOffsets(std::vector<Eigen::Vector2d> offsets);

  /// @name How the plan was made
  /// The operations that made it, as plan.json writes them (the Incision
  /// module's PlanRecipe reads and checks them; the scene keeps them as
  /// given), the SHA-256 of the CT they were applied to and the CAPS
  /// version. Empty in scenes saved before plans kept their recipe.
  ///@{
  const nlohmann::json& operations() const { return operations_; }
  /// Throws SceneError when @a operations is not a list.
  void setOperations(nlohmann::json operations);
  const std::string& ctSha256() const { return ctSha256_; }
  void setCtSha256(std::string hash);
  const std::string& softwareVersion() const { return softwareVersion_; }
  void setSoftwareVersion(std::string version);
  /// How its prediction was made, as plan.json's "simulation" object
  /// (element size, cut depth; the Incision module checks it); null when
  /// not recorded.
  const nlohmann::json& simulation() const { return simulation_; }
  /// Throws SceneError when @a simulation is neither null nor an object.
  void setSimulation(nlohmann::json simulation);
  /// How that prediction checked out and what held its wound closed, as
  /// plan.json's "prediction" and "closure" objects (PlanRecipe); null when
  /// not recorded. Throws SceneError when neither null nor an object.
  const nlohmann::json& predictionCheck() const { return predictionCheck_; }
  void setPredictionCheck(nlohmann::json check);
  const nlohmann::json& closure() const { return closure_; }
  void setClosure(nlohmann::json closure);
  ///@}

  const std::string& notes() const { return notes_; }
  void setNotes(std::string notes);

  /// The skin range map the cut path is drawn on.
  const NodeId& rangeMapId() const { return rangeMapId_; }
  void setRangeMapId(NodeId id);

protected:
  void writeFields(nlohmann::json& j) const override;
  void readFields(const nlohmann::json& j) override;

private:
  std::string procedure_;
  std::map<std::string, double> parameters_;
  std::vector<Eigen::Vector2d> cutPath_;
  std::vector<std::array<int, 4>> sutures_;
  std::vector<std::string> woundLineNames_;
  std::string generator_;
  double underminingBand_ = 0.0;
  std::string cutDepth_ = "bone";
  Eigen::Vector2d centre_ = Eigen::Vector2d::Zero();
  std::vector<Eigen::Vector2d> borderOffsets_;
  nlohmann::json operations_ = nlohmann::json::array();
  nlohmann::json predictionCheck_, closure_;
  std::string ctSha256_;
  std::string softwareVersion_;
  nlohmann::json simulation_;
  std::string notes_;
  NodeId rangeMapId_;
};

} // namespace caps
