#include "fem/ElementShape.h"

#include <stdexcept>
#include <string>

namespace caps::fem {

ElementShape ElementShape::wedge15()
{
  return ElementShape(ElementKind::Wedge15, Hex20Shape(0));
}

ElementShape ElementShape::fromConnectivity(ElementKind kind, const std::array<int, kHex20NodeCount>& nodes)
{
  if (kind == ElementKind::Wedge15)
    return wedge15();
  return Hex20Shape::fromConnectivity(nodes);
}

bool ElementShape::hasNode(int slot) const
{
  if (kind_ == ElementKind::Hex20)
    return hex_.hasNode(slot);
  if (slot < 0 || slot >= kHex20NodeCount)
    throw std::out_of_range("node slot " + std::to_string(slot) + " is outside 0..19");
  return slot < kWedge15NodeCount;
}

int ElementShape::nodeCount() const
{
  return kind_ == ElementKind::Hex20 ? hex_.nodeCount() : kWedge15NodeCount;
}

Eigen::Vector3d ElementShape::naturalCoordinates(int slot) const
{
  return kind_ == ElementKind::Hex20 ? batheNaturalCoordinates(slot) : wedge15NaturalCoordinates(slot);
}

const char* ElementShape::numberingName() const
{
  return kind_ == ElementKind::Hex20 ? "Bathe numbering" : "wedge numbering";
}

void ElementShape::values(const Eigen::Vector3d& rst, ShapeVector& h) const
{
  if (kind_ == ElementKind::Hex20)
    hex_.values(rst, h);
  else
    wedge_.values(rst, h);
}

void ElementShape::evaluate(const Eigen::Vector3d& rst, ShapeVector& h, ShapeDerivatives& dh) const
{
  if (kind_ == ElementKind::Hex20)
    hex_.evaluate(rst, h, dh);
  else
    wedge_.evaluate(rst, h, dh);
}

} // namespace caps::fem
