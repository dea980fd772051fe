#pragma once

#include <Eigen/Core>

#include <array>

namespace caps::fem {

/**
 * @brief Node numbering of the 8-to-20 variable-number-of-nodes hexahedron
 *        (Bathe), as used throughout CAPS, and its CalculiX C3D20 equivalent.
 *
 * Bathe numbering (thesis Table 4.1, Fig. 4.5, eq. 4.16), 0-based:
 *   - 0..3   corners of face 0 (t = +1),
 *   - 4..7   corners of face 1 (t = -1), each below the corner k - 4,
 *   - 8..11  mid-edge nodes of the t = +1 face,
 *   - 12..15 mid-edge nodes of the t = -1 face,
 *   - 16..19 mid-edge nodes of the edges joining the two faces.
 * Nodes 0..7 are always present; 8..19 are optional (eq. 4.16 drops g_i).
 *
 * CalculiX C3D20 (1-based, as in .inp files): 1..4 the corners at t = -1
 * counter-clockwise from (-1,-1,-1), 5..8 the same at t = +1, 9..12 and
 * 13..16 the mid-edges of the bottom and top faces, 17..20 the vertical
 * edges. Both use the same (r, s, t) axes, so a node keeps its natural
 * coordinates under the translation.
 */
inline constexpr int kHex20NodeCount = 20;
inline constexpr int kHex20CornerCount = 8;

/// C3D20 node number (1..20) of Bathe node @a batheNode (0..19).
/// Throws std::out_of_range outside 0..19.
int batheToC3D20(int batheNode);

/// Bathe node (0..19) of C3D20 node number @a c3d20Node (1..20).
/// Throws std::out_of_range outside 1..20.
int c3d20ToBathe(int c3d20Node);

/// The whole permutation: entry k is batheToC3D20(k).
const std::array<int, kHex20NodeCount>& batheToC3D20Table();

/// The inverse: entry k is c3d20ToBathe(k + 1).
const std::array<int, kHex20NodeCount>& c3d20ToBatheTable();

/// Natural coordinates (r, s, t) of Bathe node @a batheNode, each in {-1, 0, 1}
/// (thesis Table 4.1). Throws std::out_of_range outside 0..19.
Eigen::Vector3d batheNaturalCoordinates(int batheNode);

}  // namespace caps::fem
