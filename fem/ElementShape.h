#pragma once

#include "fem/ElementNumbering.h"
#include "fem/Hex20Shape.h"
#include "fem/Wedge15Shape.h"

#include <Eigen/Core>

#include <array>

namespace caps::fem {

/**
 * @brief The interpolation of one element, whatever its kind: Bathe's
 *        8-to-20 node hexahedron (Hex20Shape, also the degenerate wedge of
 *        Fig. 3.2) or the native 15-node wedge (Wedge15Shape).
 *
 * Both fill the same 20-slot vectors (slot k = node slot k of Element::nodes;
 * absent and unused slots 0), so geometry, integrators and stress recovery
 * run unchanged on either kind. A Hex20Shape converts implicitly.
 */
class ElementShape
{
public:
  ElementShape(const Hex20Shape& hex) : kind_(ElementKind::Hex20), hex_(hex) {} // NOLINT: implicit on purpose

  /// The native 15-node wedge.
  static ElementShape wedge15();
  /// Shape of an element of @a kind with node slots @a nodes (-1 absent).
  static ElementShape fromConnectivity(ElementKind kind, const std::array<int, kHex20NodeCount>& nodes);

  ElementKind kind() const { return kind_; }
  /// True if slot @a slot (0..19) is a node of this element.
  bool hasNode(int slot) const;
  int nodeCount() const;
  /// Natural coordinates of slot @a slot (Table 4.1, or the wedge numbering).
  Eigen::Vector3d naturalCoordinates(int slot) const;
  /// "Bathe numbering" or "wedge numbering", for messages.
  const char* numberingName() const;

  void values(const Eigen::Vector3d& rst, ShapeVector& h) const;
  void evaluate(const Eigen::Vector3d& rst, ShapeVector& h, ShapeDerivatives& dh) const;

private:
  ElementShape(ElementKind kind, const Hex20Shape& hex) : kind_(kind), hex_(hex) {}

  ElementKind kind_;
  Hex20Shape hex_;
  Wedge15Shape wedge_;
};

} // namespace caps::fem
