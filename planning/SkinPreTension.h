#pragma once
/// @file SkinPreTension.h
/// @brief The tension living skin carries before any cut (issue 21 item 4):
/// why an incision gapes and why a Z-plasty lengthens along one axis. A
/// pre-stress of the skin layer along the relaxed skin tension lines
/// (SkinTensionLines), held in equilibrium on the intact face
/// (fem/InitialStress.h) and released across the cut.

#include "fem/ContinuumMesher.h"
#include "fem/FacePressure.h"
#include "fem/InitialStress.h"
#include "fem/SurfaceMesh.h"
#include "planning/SkinChart.h"

#include <Eigen/Core>

#include <functional>
#include <string>
#include <vector>

namespace caps::planning {

class SkinTensionLines;

/**
 * @brief How much tension the skin carries and in which directions.
 *
 * A membrane tension of the skin layer (region 0 of the plan's model), in
 * force per length of skin (N/mm; N/m in what people read) as it is
 * measured in vivo, carried as the stress S0 = (T_along d d^T + T_across
 * c c^T) / h in each skin element, h the skin layer's thickness under it,
 * d the local tension line on the skin's tangent plane, c across it on
 * that plane. So the model's choice of layer thickness does not change the
 * tension. Skin is tenser along its tension lines than across them: a
 * round wound opens into an ellipse long along the lines (Langer 1861;
 * Deroy et al., J. Mech. Behav. Biomed. Mater. 2017, on dog skin), and a
 * cut along them gapes less. Default magnitudes: kSkinPreTensionSource.
 */
struct SkinPreTension
{
  double alongLines = 0.010;  ///< N/mm (10 N/m), along the tension lines
  double acrossLines = 0.005; ///< N/mm, across them
  /// Whether the tension follows the relaxed skin tension lines; false: the
  /// same in every direction, the mean of the two.
  bool followsLines = true;
  /// The tension line's direction at a skin point, in the chart metric
  /// (u = r dθ, v = dz; SkinTensionLines::directionAt()). Empty:
  /// simulatePlan() places the lines from the face's landmarks
  /// (seg::placeLandmarks, FaceLayout), or, where they cannot be found,
  /// takes the skin isotropic and says so.
  std::function<Eigen::Vector2d(const SkinPoint&)> lineDirection;

  /// The default magnitudes, directions from @a lines (kept by pointer:
  /// @a lines must outlive the result) or, when null, placed by the plan's
  /// simulation.
  static SkinPreTension facial(const SkinTensionLines* lines = nullptr);
  bool anisotropic() const { return followsLines && bool(lineDirection) && alongLines != acrossLines; }
  /// Throws std::invalid_argument unless both tensions are finite, >= 0
  /// and at most 1 N/mm (a thousand N/m, beyond any skin).
  void validate() const;
  /// "10 N/m along the relaxed skin tension lines, 5 N/m across them" or
  /// "7.5 N/m in every direction", with @a why the lines are not followed
  /// when they were to be and are not known.
  std::string describe(const std::string& why = {}) const;
};

/// Where the default magnitudes come from, for every output that states them.
inline constexpr const char* kSkinPreTensionSource =
  "the tension is an in-vivo estimate, not a measurement of this patient: Flynn, Taberner and Nielsen "
  "(Biomech. Model. Mechanobiol. 10:27-38, 2011) found the largest in-vivo skin tension 5.6-11.4 N/m on the "
  "human arm with a force-sensing micro-robot and a finite element model; no in-vivo value for the face is "
  "published that we know of. The default takes 10 N/m along the relaxed skin tension lines and half that "
  "across them (skin is tenser along its lines: Langer 1861; the ratio of 2 is our assumption), spread over "
  "the thickness of the model's skin layer.";

/**
 * @brief The pre-stress S0 of every element of a plan's model: the skin
 *        layer's (layer 0) from @a tension at the element's chart centroid,
 *        on the tangent plane of its skin face, over the layer's thickness
 *        there; zero in the deeper layers.
 */
fem::InitialStress skinPreStress(const fem::ContinuumMesh& continuum, const fem::SurfaceMesh& surface,
                                 const SkinChart& chart, const SkinPreTension& tension);

/**
 * @brief The faces the cut opened in the skin layer: the boundary faces of
 *        layer-0 elements whose nodes all lie on the wound (the hole loop's
 *        vertex columns and its border edges' columns), not their top (the
 *        skin surface). They carried the traction S0 N in the intact skin.
 */
std::vector<fem::ElementFace> woundFaces(const fem::ContinuumMesh& continuum, const fem::SurfaceMesh& surface);

} // namespace caps::planning
