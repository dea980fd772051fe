#include "fem/Mesh.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace caps::fem {

ElementCoordinates Mesh::elementCoordinates(std::size_t e) const
{
  ElementCoordinates x;
  const Element& el = elements[e];
  for (int k = 0; k < kHex20NodeCount; ++k)
  {
    if (el.nodes[k] >= 0)
      x.row(k) = nodes.col(el.nodes[k]).transpose();
    else
      x.row(k).setZero();
  }
  return x;
}

void validateMesh(const Mesh& mesh, const MaterialTable& materials)
{
  for (Eigen::Index i = 0; i < mesh.nodes.cols(); ++i)
  {
    if (!mesh.nodes.col(i).allFinite())
    {
      std::ostringstream m;
      m << "node " << i << " has a non-finite coordinate (" << mesh.nodes(0, i) << ", " << mesh.nodes(1, i) << ", "
        << mesh.nodes(2, i) << ")";
      throw std::invalid_argument(m.str());
    }
  }
  for (const auto& [region, material] : materials)
  {
    const std::string context = "material of region " + std::to_string(region);
    material.validate(context.c_str());
  }
  const Eigen::Index n = mesh.nodeCount();
  for (std::size_t e = 0; e < mesh.elements.size(); ++e)
  {
    const Element& el = mesh.elements[e];
    const bool wedge = el.kind == ElementKind::Wedge15;
    for (int k = 0; k < kHex20NodeCount; ++k)
    {
      const int node = el.nodes[std::size_t(k)];
      if (wedge && k >= kWedge15NodeCount)
      {
        if (node != -1)
          throw std::invalid_argument("element " + std::to_string(e) + " is a 15-node wedge but uses slot " +
                                      std::to_string(k) + " (slots 15..19 must be -1)");
        continue;
      }
      // Hex20: corners 0..7 required, mid-sides optional; Wedge15: all 15 required.
      const bool required = wedge || k < kHex20CornerCount;
      if (node < -1 || node >= n || (node == -1 && required))
      {
        std::ostringstream m;
        m << "element " << e << ": local node " << k << " (" << (wedge ? "wedge" : "Bathe")
          << " numbering) refers to node " << node << ", but the mesh has nodes 0.." << n - 1;
        if (node == -1 && required)
          m << (wedge ? " (a native wedge needs all 15 nodes)" : " (corner nodes 0..7 are required)");
        throw std::invalid_argument(m.str());
      }
    }
    if (materials.find(el.region) == materials.end())
    {
      throw std::invalid_argument("element " + std::to_string(e) + " is in region " + std::to_string(el.region) +
                                  ", which has no material");
    }
  }
}

namespace {

/// Bathe slot at natural coordinates @a c (each -1, 0 or 1).
int batheAt(const std::array<int, 3>& c)
{
  for (int k = 0; k < kHex20NodeCount; ++k)
  {
    const Eigen::Vector3d n = batheNaturalCoordinates(k);
    if (int(n[0]) == c[0] && int(n[1]) == c[1] && int(n[2]) == c[2])
      return k;
  }
  throw std::logic_error("no Bathe node at these natural coordinates");
}

/// Natural coordinates with value @a va on axis a, @a vb on axis b, @a vc on axis c.
std::array<int, 3> on(int a, int va, int b, int vb, int c, int vc)
{
  std::array<int, 3> x{};
  x[std::size_t(a)] = va;
  x[std::size_t(b)] = vb;
  x[std::size_t(c)] = vc;
  return x;
}

} // namespace

bool degenerateWedgeSlots(const Element& el, const Eigen::Matrix3Xd& x, std::array<int, kWedge15NodeCount>& slots)
{
  if (el.kind != ElementKind::Hex20)
    return false;
  int distinctCorners = 0;
  for (int k = 0; k < kHex20CornerCount; ++k)
  {
    bool first = true;
    for (int j = 0; j < k; ++j)
      first = first && el.nodes[std::size_t(j)] != el.nodes[std::size_t(k)];
    distinctCorners += first;
  }
  if (distinctCorners != kWedge15CornerCount)
    return false;
  auto node = [&](const std::array<int, 3>& c) { return el.nodes[std::size_t(batheAt(c))]; };
  for (int a = 0; a < 3; ++a) // axis along which two edges collapse
    for (int b = 0; b < 3; ++b)
    {
      if (b == a)
        continue;
      const int c = 3 - a - b; // extrusion axis
      for (int beta : {-1, 1})
      {
        // Edges along a at b = beta, on the faces c = -1 and c = +1, collapsed.
        bool collapsed = true;
        for (int gamma : {-1, 1})
          collapsed = collapsed && node(on(a, -1, b, beta, c, gamma)) == node(on(a, 1, b, beta, c, gamma));
        if (!collapsed)
          continue;
        // The other four corners distinct from each other and from the apexes.
        std::vector<int> corners;
        for (int gamma : {-1, 1})
          for (int alpha : {-1, 1, 0})
            corners.push_back(alpha == 0 ? node(on(a, -1, b, beta, c, gamma)) : node(on(a, alpha, b, -beta, c, gamma)));
        bool distinct = true;
        for (std::size_t i = 0; i < corners.size(); ++i)
          for (std::size_t j = i + 1; j < corners.size(); ++j)
            distinct = distinct && corners[i] != corners[j];
        if (!distinct)
          continue;
        // Triangle on face c = gamma: apex P (b = beta), Q (a = -1, b = -beta), R (a = +1, b = -beta).
        int qa = -1, ra = 1;
        {
          const Eigen::Vector3d p = x.col(node(on(a, -1, b, beta, c, -1)));
          const Eigen::Vector3d q = x.col(node(on(a, qa, b, -beta, c, -1)));
          const Eigen::Vector3d r = x.col(node(on(a, ra, b, -beta, c, -1)));
          const Eigen::Vector3d top = x.col(node(on(a, -1, b, beta, c, 1)));
          // Normal of (0, 1, 2) points away from (3, 4, 5).
          if ((q - p).cross(r - p).dot(top - p) > 0)
            std::swap(qa, ra);
        }
        auto corner = [&](int i, int gamma) {
          return i == 0 ? on(a, -1, b, beta, c, gamma) : on(a, i == 1 ? qa : ra, b, -beta, c, gamma);
        };
        std::size_t k = 0;
        for (int gamma : {-1, 1})
          for (int i = 0; i < 3; ++i)
            slots[k++] = batheAt(corner(i, gamma));
        for (int gamma : {-1, 1})
        {
          slots[k++] = batheAt(on(a, qa, b, 0, c, gamma));    // P-Q
          slots[k++] = batheAt(on(a, 0, b, -beta, c, gamma)); // Q-R
          slots[k++] = batheAt(on(a, ra, b, 0, c, gamma));    // R-P
        }
        slots[k++] = batheAt(on(a, -1, b, beta, c, 0)); // P along c (either collapsed slot)
        slots[k++] = batheAt(on(a, qa, b, -beta, c, 0));
        slots[k++] = batheAt(on(a, ra, b, -beta, c, 0));
        return true;
      }
    }
  return false;
}

Mesh withNativeWedges(const Mesh& mesh)
{
  Mesh out = mesh;
  std::array<int, kWedge15NodeCount> slots{};
  for (std::size_t e = 0; e < mesh.elements.size(); ++e)
  {
    const Element& el = mesh.elements[e];
    if (!degenerateWedgeSlots(el, mesh.nodes, slots))
      continue;
    bool complete = true;
    for (int k = kWedge15CornerCount; k < kWedge15NodeCount; ++k)
      complete = complete && el.nodes[std::size_t(slots[std::size_t(k)])] >= 0;
    if (!complete)
      continue;
    Element wedge;
    wedge.kind = ElementKind::Wedge15;
    wedge.region = el.region;
    wedge.nodes.fill(-1);
    for (int k = 0; k < kWedge15NodeCount; ++k)
      wedge.nodes[std::size_t(k)] = el.nodes[std::size_t(slots[std::size_t(k)])];
    // Every slot of the brick must land on a wedge node: a distinct node on
    // a collapsed edge would be dropped.
    for (int n : el.nodes)
    {
      if (n < 0)
        continue;
      if (std::find(wedge.nodes.begin(), wedge.nodes.end(), n) == wedge.nodes.end())
        throw std::invalid_argument("element " + std::to_string(e) + " is a degenerate wedge whose node " +
                                    std::to_string(n) + " lies on a collapsed edge; a 15-node wedge cannot hold it");
    }
    out.elements[e] = wedge;
  }
  return out;
}

} // namespace caps::fem
