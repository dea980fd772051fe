#pragma once

#include <Eigen/Core>

#include <array>
#include <cstdint>

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

/**
 * @brief How an Element's node slots are read.
 *
 * Hex20: Bathe's 8-to-20 node hexahedron above; a wedge is the degenerate
 * hexahedron of thesis Fig. 3.2 (repeated corner numbers). Wedge15: the
 * native 15-node serendipity wedge (pentahedron) in the wedge numbering
 * below, slots 15..19 unused (-1).
 */
enum class ElementKind : std::uint8_t
{
  Hex20 = 0,
  Wedge15 = 1
};

/**
 * @brief Node numbering of the native 15-node wedge, laid out like Bathe's
 *        hexahedron (top face first) so the two read alike.
 *
 * Natural coordinates (r, s, t): (r, s) on the triangle r, s >= 0,
 * r + s <= 1 (area coordinates L1 = 1 - r - s, L2 = r, L3 = s), t in
 * [-1, 1] along the extrusion. 0-based:
 *   - 0..2   corners of the t = +1 triangle at (r, s) = (0,0), (1,0), (0,1),
 *   - 3..5   corners of the t = -1 triangle, each below corner k - 3,
 *   - 6..8   mid-edges 0-1, 1-2, 2-0 of the t = +1 triangle,
 *   - 9..11  mid-edges 3-4, 4-5, 5-3 of the t = -1 triangle,
 *   - 12..14 mid-edges 0-3, 1-4, 2-5 of the edges along t.
 * A wedge with positive det J has the right-hand normal of triangle
 * (0, 1, 2) pointing away from triangle (3, 4, 5); this is exactly the
 * VTK_QUADRATIC_WEDGE point order.
 *
 * CalculiX C3D15 (1-based, ccx shape15w: xi = r, eta = s, zeta = t): 1..3
 * the corners at t = -1, 4..6 those at t = +1, 7..9 and 10..12 the
 * mid-edges of the bottom and top triangles, 13..15 the edges along t.
 */
inline constexpr int kWedge15NodeCount = 15;
inline constexpr int kWedge15CornerCount = 6;

/// C3D15 node number (1..15) of wedge node @a wedgeNode (0..14).
/// Throws std::out_of_range outside 0..14.
int wedge15ToC3D15(int wedgeNode);

/// Wedge node (0..14) of C3D15 node number @a c3d15Node (1..15).
/// Throws std::out_of_range outside 1..15.
int c3d15ToWedge15(int c3d15Node);

/// Natural coordinates (r, s, t) of wedge node @a wedgeNode: r, s in
/// {0, 1/2, 1}, t in {-1, 0, 1}. Throws std::out_of_range outside 0..14.
Eigen::Vector3d wedge15NaturalCoordinates(int wedgeNode);

} // namespace caps::fem
