#pragma once
/// @file MetalArtefacts.h
/// @brief Metal in a head CT (dental fillings, crowns, plates, a head
/// holder's screws), or contrast still undiluted in a vein of the neck, and
/// the slices its streaks spoil.
///
/// Metal attenuates beyond the scanner's range: its voxels sit at or near
/// the top of the HU scale (3071 on 12-bit scanners), far above enamel and
/// cortical bone (under about 2500 HU); so does iodinated contrast while a
/// bolus is still undiluted in the arm and neck veins. Its beam hardening and photon
/// starvation throw bright and dark streaks across the whole axial slice it
/// lies in, so the skin and the bone found in those slices (spikes and holes
/// in the range maps) are not measurements to trust. A finding says where the
/// metal is and which slices are spoiled; what lies in them is flagged, not
/// measured as if it were sound.

#include <string>
#include <vector>

#include <Eigen/Core>

class vtkImageData;

namespace caps::seg {

/// One piece of metal: a connected group of voxels at or above the metal HU.
struct MetalPiece
{
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero(); ///< world (LPS) mm
  int voxels = 0;
  double peakHu = 0.0;
  /// The slices it lies in (0-based slice index along the image's third
  /// axis, the scanner's table axis), and those its streaks spoil: a margin
  /// of slices either side, for the streaks' spread through the slice
  /// thickness and the reconstruction kernel.
  int firstSlice = 0, lastSlice = 0;
  int firstSpoiled = 0, lastSpoiled = 0;
};

struct MetalOptions
{
  double metalHu = 3000.0;   ///< at or above: metal (enamel and cortical bone stay under)
  int smallestPiece = 4;     ///< voxels; fewer are noise or a saturated speck of enamel
  double streakMargin = 5.0; ///< mm either side of the metal's slices that streaks spoil
};

/// The metal pieces of @a ct (HU, one component, any scalar type), largest
/// first; empty when there is none.
/// @throws std::invalid_argument for an image without voxels.
std::vector<MetalPiece> findMetal(vtkImageData* ct, const MetalOptions& options = {});

/// The piece whose spoiled slices hold the world point @a p (LPS mm) of @a ct,
/// or nullptr.
const MetalPiece* streaksAt(const std::vector<MetalPiece>& pieces, vtkImageData* ct, const Eigen::Vector3d& p);

/// "metal or undiluted contrast (3071.0 HU, 57 voxels) at (12.0, -80.5,
/// 40.2) mm: its streaks spoil the slices from z 35.2 to 45.2 mm".
std::string describe(const MetalPiece& piece, vtkImageData* ct);

} // namespace caps::seg
