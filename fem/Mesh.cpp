#include "fem/Mesh.h"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace caps::fem {

ElementCoordinates Mesh::elementCoordinates(std::size_t e) const {
  ElementCoordinates x;
  const Element& el = elements[e];
  for (int k = 0; k < kHex20NodeCount; ++k) {
    if (el.nodes[k] >= 0)
      x.row(k) = nodes.col(el.nodes[k]).transpose();
    else
      x.row(k).setZero();
  }
  return x;
}

void validateMesh(const Mesh& mesh, const MaterialTable& materials) {
  for (Eigen::Index i = 0; i < mesh.nodes.cols(); ++i) {
    if (!mesh.nodes.col(i).allFinite()) {
      std::ostringstream m;
      m << "node " << i << " has a non-finite coordinate (" << mesh.nodes(0, i) << ", "
        << mesh.nodes(1, i) << ", " << mesh.nodes(2, i) << ")";
      throw std::invalid_argument(m.str());
    }
  }
  for (const auto& [region, material] : materials) {
    const std::string context = "material of region " + std::to_string(region);
    material.validate(context.c_str());
  }
  const Eigen::Index n = mesh.nodeCount();
  for (std::size_t e = 0; e < mesh.elements.size(); ++e) {
    const Element& el = mesh.elements[e];
    for (int k = 0; k < kHex20NodeCount; ++k) {
      const int node = el.nodes[k];
      if (node < -1 || node >= n || (node == -1 && k < kHex20CornerCount)) {
        std::ostringstream m;
        m << "element " << e << ": local node " << k << " (Bathe numbering) refers to node " << node
          << ", but the mesh has nodes 0.." << n - 1;
        if (node == -1 && k < kHex20CornerCount) m << " (corner nodes 0..7 are required)";
        throw std::invalid_argument(m.str());
      }
    }
    if (materials.find(el.region) == materials.end()) {
      throw std::invalid_argument("element " + std::to_string(e) + " is in region " +
                                  std::to_string(el.region) + ", which has no material");
    }
  }
}

}  // namespace caps::fem
