#include "fem/Wedge15Shape.h"

namespace caps::fem {

namespace {

enum class NodeType
{
  Corner,
  TriangleEdge,
  AxialEdge
};

struct WedgeNode
{
  NodeType type;
  int i, j;    // area coordinates involved (j only for a triangle edge)
  double side; // t of the node's triangle (+1, -1), 0 on an axial edge
};

// Wedge numbering of ElementNumbering.h: L0 = 1 - r - s at (0,0), L1 = r at (1,0), L2 = s at (0,1).
constexpr WedgeNode kNodes[kWedge15NodeCount] = {
  {NodeType::Corner, 0, 0, 1},        {NodeType::Corner, 1, 0, 1},        {NodeType::Corner, 2, 0, 1},
  {NodeType::Corner, 0, 0, -1},       {NodeType::Corner, 1, 0, -1},       {NodeType::Corner, 2, 0, -1},
  {NodeType::TriangleEdge, 0, 1, 1},  {NodeType::TriangleEdge, 1, 2, 1},  {NodeType::TriangleEdge, 2, 0, 1},
  {NodeType::TriangleEdge, 0, 1, -1}, {NodeType::TriangleEdge, 1, 2, -1}, {NodeType::TriangleEdge, 2, 0, -1},
  {NodeType::AxialEdge, 0, 0, 0},     {NodeType::AxialEdge, 1, 0, 0},     {NodeType::AxialEdge, 2, 0, 0},
};

// dL_i/dr and dL_i/ds.
constexpr double kDLdr[3] = {-1.0, 1.0, 0.0};
constexpr double kDLds[3] = {-1.0, 0.0, 1.0};

} // namespace

void Wedge15Shape::values(const Eigen::Vector3d& rst, ShapeVector& h) const
{
  ShapeDerivatives dh;
  evaluate(rst, h, dh);
}

void Wedge15Shape::evaluate(const Eigen::Vector3d& rst, ShapeVector& h, ShapeDerivatives& dh) const
{
  const double l[3] = {1.0 - rst[0] - rst[1], rst[0], rst[1]};
  const double t = rst[2];
  h.setZero();
  dh.setZero();
  for (int k = 0; k < kWedge15NodeCount; ++k)
  {
    const WedgeNode& n = kNodes[k];
    double dl[3] = {0.0, 0.0, 0.0}; // dh/dL_m
    double dt = 0.0;                // dh/dt
    switch (n.type)
    {
    case NodeType::Corner:
    {
      const double li = l[n.i], tau = n.side * t;
      h[k] = 0.5 * li * (1.0 + tau) * (2.0 * li - 2.0 + tau);
      dl[n.i] = 0.5 * (1.0 + tau) * (4.0 * li - 2.0 + tau);
      dt = 0.5 * li * n.side * (2.0 * li - 1.0 + 2.0 * tau);
      break;
    }
    case NodeType::TriangleEdge:
    {
      const double tau = n.side * t;
      h[k] = 2.0 * l[n.i] * l[n.j] * (1.0 + tau);
      dl[n.i] = 2.0 * l[n.j] * (1.0 + tau);
      dl[n.j] = 2.0 * l[n.i] * (1.0 + tau);
      dt = 2.0 * l[n.i] * l[n.j] * n.side;
      break;
    }
    case NodeType::AxialEdge:
      h[k] = l[n.i] * (1.0 - t * t);
      dl[n.i] = 1.0 - t * t;
      dt = -2.0 * l[n.i] * t;
      break;
    }
    for (int m = 0; m < 3; ++m)
    {
      dh(k, 0) += dl[m] * kDLdr[m];
      dh(k, 1) += dl[m] * kDLds[m];
    }
    dh(k, 2) = dt;
  }
}

} // namespace caps::fem
