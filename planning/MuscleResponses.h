#pragma once
/// @file MuscleResponses.h
/// @brief Real-time expressions by superposition (thesis §3.1.2): a model is
/// factored once, solved once per muscle at unit activation, and any mix of
/// activations is the weighted sum of those responses, on the whole model
/// and on its display skin.

#include <vector>

#include <Eigen/Core>

#include "fem/DisplaySurface.h"
#include "fem/MuscleLoad.h"
#include "fem/StaticAnalysis.h"

namespace caps::expression {

/// @class MuscleResponses
/// @brief The displacement of a linear model under each muscle alone at
/// activation 1 (its force functions at the loads given).
///
/// The model is linear (§4.6), so activations a_k, each scaling muscle k's
/// loads, give U(a) = Σ a_k U_k exactly: one factorisation and one
/// substitution per muscle replace a solve per slider move.
class MuscleResponses
{
public:
  MuscleResponses() = default;
  /// Solves @a analysis (prepared: factored) for every muscle of @a muscles,
  /// each a set of force functions (eq. 4.40–4.42), all in one
  /// multi-column substitution. @throws std::logic_error if the analysis
  /// was not prepared; std::invalid_argument for a bad muscle
  /// (fem::validateMuscle names it).
  MuscleResponses(fem::LinearStaticAnalysis& analysis, const std::vector<std::vector<fem::Muscle>>& muscles);

  Eigen::Index muscleCount() const { return displacements_.cols(); }
  /// U_k: 3N × muscles, node i's (x, y, z) at rows 3i..3i+2 (mm): what
  /// muscle k adds to the model's displacement without load (zero for a
  /// model with fixed supports only; the closure for a model with sutures).
  const Eigen::MatrixXd& displacements() const { return displacements_; }
  /// R_k: the nodal loads of each muscle (N), 3N × muscles.
  const Eigen::MatrixXd& loads() const { return loads_; }
  /// What each muscle applies to the mesh (the part of its attachments inside it).
  const std::vector<std::vector<fem::MuscleForces>>& forces() const { return forces_; }

  /// Σ a_k U_k for @a activations (one per muscle). @throws std::invalid_argument for a wrong count.
  Eigen::VectorXd combined(const Eigen::VectorXd& activations) const;

private:
  Eigen::MatrixXd displacements_;
  Eigen::MatrixXd loads_;
  std::vector<std::vector<fem::MuscleForces>> forces_;
};

/// @class ExpressionSurface
/// @brief A display skin (fem::DisplaySurface, §4.7) whose vertices move with
/// the activations at display rate: each muscle's response is interpolated
/// to the vertices once (eq. 4.14), so a slider move is one small
/// matrix-vector product, no finite element work.
class ExpressionSurface
{
public:
  ExpressionSurface() = default;
  /// @a surface: the skin faces to show (its undeformed positions and range
  /// detail are kept); @a responses of the same mesh.
  ExpressionSurface(const fem::Mesh& mesh, fem::DisplaySurface surface, const MuscleResponses& responses);
  /// The same for any linear responses of @a mesh (3N × k: a muscle's, a
  /// fingertip's unit travel) on top of @a base (3N, e.g. the closure of a
  /// plan after the operation; empty: none).
  /// @throws std::invalid_argument when @a responses or @a base are not of @a mesh.
  ExpressionSurface(const fem::Mesh& mesh, fem::DisplaySurface surface, const Eigen::MatrixXd& responses,
                    const Eigen::VectorXd& base = {});

  const fem::DisplaySurface& surface() const { return surface_; }
  Eigen::Index vertexCount() const { return surface_.vertexCount(); }
  Eigen::Index muscleCount() const { return vertexResponses_.cols(); }
  /// The displacement of every vertex per muscle: 3V × muscles.
  const Eigen::MatrixXd& vertexResponses() const { return vertexResponses_; }

  /// Vertex positions (3 × V) under @a activations: undeformed (with the
  /// range detail when @a rangeDetail) plus the base plus Σ a_k D_k. @a out is resized only
  /// when needed, so a caller reusing it does not allocate.
  /// @throws std::invalid_argument for a wrong number of activations.
  void positions(const Eigen::VectorXd& activations, bool rangeDetail, Eigen::Matrix3Xd& out) const;

private:
  fem::DisplaySurface surface_;
  Eigen::MatrixXd vertexResponses_;
  Eigen::VectorXd vertexBase_; ///< 3V, empty when there is no base
};

} // namespace caps::expression
