#pragma once

#include "fem/ElementGeometry.h"
#include "fem/Mesh.h"

#include <Eigen/Core>

#include <optional>
#include <vector>

namespace caps::fem {

/**
 * @brief A body coordinate point (e, r, s, t) (thesis §4.2.4): the element
 *        that holds the point and its natural coordinates in it, each in
 *        [-1, 1] for a brick (r, s >= 0, r + s <= 1, t in [-1, 1] for a
 *        native 15-node wedge). It names the same material point however the
 *        body deforms.
 */
struct BodyPoint
{
  int element = -1;
  Eigen::Vector3d rst = Eigen::Vector3d::Zero();
};

/// Undeformed world point of @a p, eq. 4.13: x = sum_k h_k(r, s, t) x_k.
/// Throws std::invalid_argument for an element index out of range or
/// natural coordinates outside the element (or not finite).
Eigen::Vector3d worldPoint(const Mesh& mesh, const BodyPoint& p);

/// Displacement at @a p, eq. 4.14: u = sum_k h_k(r, s, t) u_k, with @a u the
/// 3N nodal displacement vector (node i at 3i..3i+2). Throws
/// std::invalid_argument as worldPoint(), or if @a u is not of size 3N.
Eigen::Vector3d displacementAt(const Mesh& mesh, const Eigen::VectorXd& u, const BodyPoint& p);

/// Displaced world point of @a p, eq. 4.15: x' = sum_k h_k(r, s, t) (x_k + u_k).
Eigen::Vector3d displacedWorldPoint(const Mesh& mesh, const Eigen::VectorXd& u, const BodyPoint& p);

/**
 * @brief Finds the body coordinates of world points: the inverse of eq. 4.13.
 *
 * Built once per mesh (it copies the element geometry, so the mesh may go
 * away), then queried for any number of points, e.g. every skin vertex to
 * carry it through the deformation (locate, then displacedWorldPoint).
 *
 * Each element gets a bounding box that provably holds its curved shape:
 * the box of x on a 5 x 5 x 5 grid in (r, s, t) ([0, 1]^2 x [-1, 1] for a
 * native wedge), grown by the bound on how far the mapping can leave the
 * multilinear interpolant of that grid, (1/8) sum_i max |second difference
 * along i| (the 8-to-20 node and the 15-node wedge functions are at most
 * quadratic along each of r, s, t). A uniform grid of cells over the mesh
 * lists the boxes. For each element whose box holds the point, Newton's
 * method on x(r, s, t) = p starts from the nearest of 27 (wedge: 12) points
 * inside the element and accepts the point if it converges to within
 * kNaturalTolerance of the natural domain (then clamped into it). A point
 * on a face shared by elements goes to the element where it lies deepest,
 * ties to the lowest element index.
 *
 * Degenerate (wedge) 20-node elements work: the Newton step falls back to
 * least squares where the Jacobian is singular (a collapsed edge). Native
 * 15-node wedges (ElementKind::Wedge15) work too.
 */
class BodyCoordinateLocator
{
public:
  /// Throws std::invalid_argument for an element referring to a node that
  /// does not exist (or lacking a corner), or a non-finite node coordinate.
  explicit BodyCoordinateLocator(const Mesh& mesh);

  /// Body coordinates of @a world, or nothing if no element holds it.
  std::optional<BodyPoint> find(const Eigen::Vector3d& world) const;

  /// The same, but throws std::out_of_range naming the point (and the
  /// nearest element, when one is close) if it lies outside the mesh.
  BodyPoint locate(const Eigen::Vector3d& world) const;

  /// Natural-coordinate slack for points on an element's faces.
  static constexpr double kNaturalTolerance = 1e-9;

private:
  struct Candidate
  {
    BodyPoint point;
    double outside = 0.0;  ///< distance outside the natural domain (<= 0 inside)
    double residual = 0.0; ///< |x(r, s, t) - world|, mm
    bool converged = false;
  };
  Candidate newton(std::size_t element, const Eigen::Vector3d& world) const;
  std::vector<int> candidates(const Eigen::Vector3d& world) const;

  std::vector<ElementKind> kinds_;
  std::vector<ElementShape> shapes_;
  std::vector<ElementCoordinates> coordinates_;
  std::vector<Eigen::Matrix3Xd> starts_; ///< world points of the Newton starts
  std::vector<Eigen::Vector3d> boxMin_, boxMax_;
  std::vector<double> size_; ///< bounding box diagonal, mm (tolerance scale)
  Eigen::Vector3d gridMin_ = Eigen::Vector3d::Zero(), cell_ = Eigen::Vector3d::Ones();
  Eigen::Vector3i cells_ = Eigen::Vector3i::Ones();
  std::vector<std::vector<int>> bins_; ///< elements whose box meets each cell
};

} // namespace caps::fem
