#pragma once

#include "fem/Assembly.h"
#include "fem/Mesh.h"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace caps::fem {

/**
 * @brief One muscle force function (thesis §4.6.2, Table 4.7, eq. 4.40):
 *        a spherical insertion and origin in world space and a load.
 *
 * Facial muscles mesh with the soft tissue rather than pulling on a point,
 * so the force acts as a body force over each attachment sphere. At a world
 * point q (eq. 4.40):
 *
 *   f(q) = w(q, p_i, r_i) l (p_o - p_i) + w(q, p_o, r_o) l (p_i - p_o)   [N/mm^3]
 *
 * The insertion tissue is pulled towards the origin and the origin tissue
 * towards the insertion, so a muscle with both ends in the tissue applies
 * equal and opposite forces when its two spheres hold the same tissue
 * volume. As in the thesis the force density is l times the unnormalised
 * vector p_o - p_i: @a load is in N/mm^4 and the pull grows with the
 * origin-insertion distance. Several functions arranged along a sheet or
 * ring approximate a whole muscle (eq. 4.42 sums them).
 *
 * An origin in bone applies no force on the soft tissue: originRadius = 0
 * (the thesis' convention).
 */
struct Muscle
{
  std::string name;                                    ///< for messages and reports; may be empty
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();    ///< p_o, world mm
  double originRadius = 0.0;                           ///< r_o, mm; 0: origin in bone (no force)
  Eigen::Vector3d insertion = Eigen::Vector3d::Zero(); ///< p_i, world mm
  double insertionRadius = 0.0;                        ///< r_i, mm; > 0
  double load = 0.0;                                   ///< l, N/mm^4 (>= 0: a muscle only pulls)
  /// Width b (mm) of a smooth fall-off outside each sphere (thesis: "make the
  /// muscle force fall off over a region based on the distance from the
  /// attachment shape"); 0 gives the sharp sphere of eq. 4.41.
  double falloff = 0.0;
};

/**
 * @brief Weight of an attachment sphere at distance @a distance from its
 *        centre (eq. 4.41, extended by a fall-off).
 *
 * falloff = 0: 1 if distance < radius, else 0 (eq. 4.41).
 * falloff = b > 0: 1 up to the sphere, then the C1 cosine taper
 * (1 + cos(pi (d - r) / b)) / 2 down to 0 at d = r + b, so the load has no
 * jump at the sphere surface and converges faster under mesh refinement.
 * A radius of 0 gives 0 everywhere (an origin in bone).
 */
double attachmentWeight(double distance, double radius, double falloff);

/**
 * @brief Integral of attachmentWeight over all space (mm^3): the volume an
 *        attachment acts on when it lies wholly inside the tissue.
 *
 * 4 pi [ r^3/3 + ((r+b)^3 - r^3)/6 - (2 r b^2 + b^3)/pi^2 ] (the cosine
 * taper integrated over spherical shells); 4/3 pi r^3 for b = 0.
 */
double attachmentVolume(double radius, double falloff);

/// Force per unit volume (N/mm^3) of @a muscle at world point @a q, eq. 4.40.
Eigen::Vector3d muscleForceDensity(const Muscle& muscle, const Eigen::Vector3d& q);

/**
 * @brief Checks one muscle; throws std::invalid_argument naming it (by
 *        @a index and name) for a non-finite value, an insertion radius <= 0,
 *        a negative origin radius, load or fall-off, or an origin that
 *        coincides with the insertion (no direction to pull in).
 */
void validateMuscle(const Muscle& muscle, std::size_t index);

/// What each muscle applies to the mesh, for reports.
struct MuscleForces
{
  double insertionVolume = 0.0;                             ///< integral of the insertion weight over the mesh, mm^3
  double originVolume = 0.0;                                ///< the same for the origin (0 in bone)
  Eigen::Vector3d insertionForce = Eigen::Vector3d::Zero(); ///< N, towards the origin
  Eigen::Vector3d originForce = Eigen::Vector3d::Zero();    ///< N, towards the insertion
};

/// Consistent nodal loads of a set of muscles and the forces they apply.
struct MuscleLoad
{
  Eigen::VectorXd load;                                 ///< 3N nodal forces (N)
  Eigen::Vector3d totalForce = Eigen::Vector3d::Zero(); ///< sum of @a load over all nodes (N)
  std::vector<MuscleForces> muscles;                    ///< one per input muscle, same order
};

/**
 * @brief Nodal loads of @a muscles summed into one vector (eq. 4.42): each
 *        element's R_m = sum_g alpha_g H^T f(x(r_g, s_g, t_g)) det J, with
 *        x the body-to-world mapping of eq. 4.13 and the Gauss rule of
 *        @a options (3 x 3 x 3, Table 4.6, by default; integrationRule()
 *        of the same level for a native wedge), as for gravity
 *        (eq. 4.35-4.39).
 *
 * Only the part of each sphere inside the mesh is loaded: an attachment cut
 * by the skin or the bone surface applies the force of the intersection,
 * reported in MuscleForces. The interpolation functions sum to one, so
 * totalForce is the Gauss quadrature of f over the mesh volume.
 * The mesh is assumed validated (validateMesh); the muscles are validated
 * here (validateMuscle). Throws ElementError for an element inverted at an
 * integration point inside an attachment.
 */
MuscleLoad assembleMuscleLoad(const Mesh& mesh, const std::vector<Muscle>& muscles,
                              const AssemblyOptions& options = {});

} // namespace caps::fem
