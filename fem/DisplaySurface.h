#pragma once
/// @file DisplaySurface.h
/// @brief Element faces subdivided for display, every vertex kept in body
/// coordinates with the data of thesis Table 4.9 precalculated (§4.7).

#include "fem/BodyCoordinates.h"
#include "fem/ContinuumMesher.h"
#include "fem/FacePressure.h"
#include "fem/HyperelasticMaterial.h"
#include "fem/LinearElasticMaterial.h"
#include "fem/Mesh.h"

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <array>
#include <functional>
#include <vector>

namespace caps::fem {

/// Six values per column: strain or stress in Voigt order xx, yy, zz, xy,
/// yz, zx (engineering shear strain), as everywhere in fem/.
using Matrix6Xd = Eigen::Matrix<double, 6, Eigen::Dynamic>;

/**
 * @brief The boundary faces of @a mesh whose nodes all belong to @a nodes:
 *        faces no other element shares (compared by their distinct corner
 *        nodes) and that are not collapsed to an edge or a point (the
 *        degenerate side of a Fig. 3.2 wedge). In element order, faces
 *        ascending. Node indices out of range are ignored.
 */
std::vector<ElementFace> boundaryFacesOnNodes(const Mesh& mesh, const std::vector<int>& nodes);

/// The skin of a continuum mesh (§4.5.2): the top face (t = +1, face 2 of
/// both the hexahedron and the native wedge) of every element of layer 0.
std::vector<ElementFace> skinFaces(const ContinuumMesh& continuum);

/// How display positions are mapped (the thesis's mapping modes, §4.7).
struct DisplayMapping
{
  /// Scale of the displacement added to the undeformed position: 0 shows
  /// the pre-operative (undeformed) shape, 1 the post-operative (deformed)
  /// one, values between animate the transition.
  double scale = 0.0;
  /// Add the range displacement vector (range detail) of each vertex.
  bool rangeDetail = false;
};

/**
 * @class DisplaySurface
 * @brief Element faces sampled at equal steps of their natural coordinates
 *        (thesis §4.7): n x n quadrilaterals per quadrilateral face, n^2
 *        triangles per triangular face of a native wedge, for a resolution n.
 *
 * Every vertex is a body point (element, r, s, t) (§4.2.4). The data of
 * thesis Table 4.9 are precalculated per vertex: the undeformed world
 * position (eq. 4.13), the range displacement (set by the caller, who knows
 * the scan), and under the current solution the displacement (eq. 4.14),
 * strain and stress. The shape function values of every vertex are kept as
 * a sparse interpolation matrix, so a new solution or a new mapping only
 * multiplies; the subdivision is never redone.
 *
 * Vertices on an edge shared by two faces (of one element or of two) are
 * one vertex: a vertex on the edge between corner nodes A and B is named by
 * (A, B, steps from the smaller of A and B), which both faces compute
 * exactly, since both parametrise the edge linearly between the same two
 * corners with the same number of steps. So the surface of a conforming
 * mesh is one connected mesh without cracks; an edge collapsed to one node
 * (a degenerate wedge) becomes that node's single vertex, and polygons left
 * with fewer than three distinct vertices are dropped. Polygons are wound so
 * their right-hand normal points out of the element (the scan directions of
 * Table 4.8), given a positive Jacobian.
 *
 * Strain and stress at a vertex: the nodal averages of the element values
 * extrapolated from the 2 x 2 x 2 Gauss points (Barlow points; the wedge's
 * 9-point rule), as recoverNodalStresses() computes them, interpolated with
 * the vertex's shape functions. Why not the element's own B U at the vertex
 * (eq. 4.47-4.48)? That value is discontinuous across element boundaries, so
 * a vertex on a shared edge would take whichever element owns it and the
 * colours would show the mesh instead of the tissue; the extrapolated and
 * averaged field is continuous, reproduces any stress linear in (r, s, t)
 * exactly, and is the better estimate at the surface (the Gauss points are
 * where the quadratic element's stresses are most accurate). The average is
 * taken within each region (recoverNodalStresses' NodalStressField::valueAt):
 * a vertex takes the field of its own element's region, so a skin vertex
 * shows the skin's stress even at a node the fat below shares, and the jump
 * across two materials is kept, not blurred. A vertex welded on an edge
 * where faces of two regions meet takes the region of the face that made it.
 *
 * @warning The surface refers to mesh nodes by index: a solution must come
 * from the same mesh (same node count).
 */
class DisplaySurface
{
public:
  DisplaySurface() = default;

  /**
   * Subdivides @a faces of @a mesh at @a resolution steps per face edge.
   * Throws std::invalid_argument for a resolution below 1, an element index
   * out of range, a face the element does not have, or (from the geometry)
   * an element that refers to a missing node.
   */
  DisplaySurface(const Mesh& mesh, const std::vector<ElementFace>& faces, int resolution);

  int resolution() const { return resolution_; }
  const std::vector<ElementFace>& faces() const { return faces_; }
  Eigen::Index vertexCount() const { return positions_.cols(); }

  /// Polygons (3 or 4 vertex indices), outward, and the face (index into
  /// faces()) each came from.
  const std::vector<std::vector<int>>& polygons() const { return polygons_; }
  const std::vector<int>& polygonFace() const { return polygonFace_; }

  /// @name Table 4.9, per vertex
  ///@{
  /// Body coordinates (element, r, s, t) of each vertex.
  const std::vector<BodyPoint>& bodyPoints() const { return bodyPoints_; }
  /// Undeformed world position, eq. 4.13 (3 x V, mm).
  const Eigen::Matrix3Xd& undeformedPositions() const { return positions_; }
  /// Range displacement: world offset to the scan data (3 x V, mm), zero
  /// until set.
  const Eigen::Matrix3Xd& rangeDetail() const { return rangeDetail_; }
  /// Displacement under the current solution (3 x V, mm), zero before one.
  const Eigen::Matrix3Xd& displacements() const { return displacements_; }
  /// Strain and stress (MPa) under the current solution (6 x V), zero
  /// before one; see the class comment for how they are recovered.
  const Matrix6Xd& strains() const { return strains_; }
  const Matrix6Xd& stresses() const { return stresses_; }
  ///@}

  /// Sets the range displacement of every vertex. Throws
  /// std::invalid_argument unless @a offsets is 3 x vertexCount() and finite.
  void setRangeDetail(const Eigen::Matrix3Xd& offsets);

  /**
   * @brief Takes a new solution: @a u holds the 3N nodal displacements of
   *        the mesh the surface was made from. Updates displacement, strain
   *        and stress of every vertex from the precalculated interpolation
   *        and element derivatives (no subdivision, no Jacobians).
   *
   * Throws std::invalid_argument for a wrong size of @a u or an element
   * region without a material in @a materials.
   */
  void setSolution(const Eigen::VectorXd& u, const MaterialTable& materials);
  /// The same for a large-deformation solution: the strain is the
  /// Green-Lagrange strain and the stress the Cauchy stress of the deformed
  /// tissue (FiniteStrainIntegrator.h), recovered at the display nodes as the
  /// linear ones are.
  void setSolution(const Eigen::VectorXd& u, const HyperelasticTable& materials);
  bool hasSolution() const { return hasSolution_; }

  /// Vertex positions for @a mapping: undeformed + scale x displacement
  /// (+ range detail).
  Eigen::Matrix3Xd positions(const DisplayMapping& mapping) const;
  /// The same into @a out, which must be 3 x vertexCount() (an interactive
  /// loop reuses it); throws std::invalid_argument otherwise.
  void positions(const DisplayMapping& mapping, Eigen::Matrix3Xd& out) const;

  /// @name Scalars to colour by (one per vertex)
  ///@{
  /// |displacement| (mm).
  Eigen::VectorXd displacementMagnitude() const;
  /// von Mises equivalent stress (MPa).
  Eigen::VectorXd vonMises() const;
  /// Mean stress (sxx + syy + szz) / 3 (MPa): the thesis's "pressure
  /// stress" up to its sign (pressure = -mean stress).
  Eigen::VectorXd meanStress() const;
  /// Volumetric strain exx + eyy + ezz: the thesis's "pressure strain"
  /// (relative change of volume, small for nearly incompressible tissue).
  Eigen::VectorXd volumetricStrain() const;
  /// Equivalent (von Mises) strain sqrt(2/3 e':e'), e' the deviatoric strain
  /// tensor: the stretch and shear a surgeon sees as tension lines, 1 x the
  /// strain in uniaxial incompressible stretch.
  Eigen::VectorXd equivalentStrain() const;
  ///@}

  /// Shape-function weights: column v holds h_k(r, s, t) of vertex v at the
  /// rows of its element's nodes (D x V, D = displayNodes().size()).
  const Eigen::SparseMatrix<double>& interpolation() const { return weights_; }
  /// Mesh nodes with a non-zero weight at some vertex (rows of interpolation()).
  const std::vector<int>& displayNodes() const { return displayNodes_; }

private:
  /// Strain and stress (Voigt, engineering shears) at one Gauss point of an
  /// element of @a region from its displacement gradient du/dX.
  using PointResponse =
    std::function<void(int region, const Eigen::Matrix3d& gradient, Vector6d& strain, Vector6d& stress)>;
  /// Both setSolution()s: @a response at every Gauss point of the support
  /// elements, extrapolated to the nodes and averaged within each region.
  void recoverAtTheDisplayNodes(const Eigen::VectorXd& u, const PointResponse& response);

  /// What setSolution() needs of one element around the display nodes: its
  /// world shape derivatives at the Gauss points and the extrapolation to
  /// its nodes (recoverNodalStresses' scheme), precalculated.
  struct SupportElement
  {
    int region = 0;
    std::array<int, kHex20NodeCount> nodes{}; ///< mesh node per slot (-1 absent)
    std::array<int, kHex20NodeCount>
      displaySlot{}; ///< row of regionWeights_ per slot (its node, this region), -1 if none
    std::array<int, kHex20NodeCount> slotWeight{};                    ///< slots sharing this slot's node (>= 1)
    std::vector<Eigen::Matrix<double, kHex20NodeCount, 3>> gradients; ///< dh/dx per Gauss point
    bool wedge = false; ///< extrapolated by wedgeExtrapolation_ (else hexExtrapolation_)
  };

  /// The constructor's state while it adds the faces (DisplaySurface.cpp).
  struct Construction;
  /// The constructor's steps: the vertices and polygons of face @a f, the
  /// interpolation weights and positions, the elements around the display nodes.
  void addFace(std::size_t f, Construction& build);
  void setWeights(const Mesh& mesh, const Construction& build);
  void addSupportElements(const Mesh& mesh, const Construction& build);

  int resolution_ = 0;
  Eigen::Index meshNodeCount_ = 0;
  std::vector<ElementFace> faces_;
  std::vector<std::vector<int>> polygons_;
  std::vector<int> polygonFace_;
  std::vector<BodyPoint> bodyPoints_;
  std::vector<int> displayNodes_;
  Eigen::SparseMatrix<double> weights_;
  /// The same weights by (display node, region of the vertex's element) rows,
  /// for the strain and stress averaged within each region.
  Eigen::SparseMatrix<double> regionWeights_;
  Eigen::Matrix3Xd positions_, rangeDetail_, displacements_;
  Matrix6Xd strains_, stresses_;
  bool hasSolution_ = false;
  std::vector<SupportElement> support_;
  Eigen::VectorXi displayElementCount_; ///< elements averaged in each row of regionWeights_
  Eigen::MatrixXd hexExtrapolation_, wedgeExtrapolation_;
};

} // namespace caps::fem
