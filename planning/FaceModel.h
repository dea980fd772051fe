#pragma once
/// @file FaceModel.h
/// @brief The whole face meshed from the skin to the bone without a plan
/// (thesis §5.3: "generate the mesh for the patient without specifying any
/// suture conditions"), so expressions can be simulated on the unoperated
/// face.

#include <string>
#include <vector>

#include "fem/ContinuumMesher.h"
#include "fem/LinearElasticMaterial.h"
#include "fem/SurfaceMesh.h"
#include "planning/PlanSimulation.h"
#include "segmentation/Landmarks.h"
#include "segmentation/RangeMap.h"

namespace caps::expression {

/// Options of meshFace(). Lengths in mm.
struct FaceModelOptions : planning::TissueDepthOptions
{
  /// Edge length of the quadrilaterals on the skin.
  double elementSize = 5.0;
  /// How far the region reaches beyond each zygion (mm of arc on the skin),
  /// below the menton and above the mid-forehead landmark.
  double lateralMargin = 15.0;
  double marginBelowMenton = 10.0;
  double marginAboveForehead = 15.0;
};

/// The face region on the cylindrical frame: θ in radians, z in mm.
struct FaceRegion
{
  double thetaMin = 0.0;
  double thetaMax = 0.0;
  double zMin = 0.0;
  double zMax = 0.0;
};

/// @brief The region meshFace() covers: from the right zygion to the left one
/// (widened by lateralMargin), from below the menton to above the forehead
/// landmark, cut to the rows where the skin map has skin across the whole
/// width. @throws std::invalid_argument naming the landmarks missing
/// (zygion_left, zygion_right, menton, forehead) or a region that is empty.
FaceRegion faceRegion(const std::vector<seg::Landmark>& landmarks, const seg::RangeMap& skin,
                      const FaceModelOptions& options = {});

/// The meshed face.
struct FaceMesh
{
  FaceRegion region;
  /// The chart (planning::SkinChart) the surface mesh is drawn in: u = r0 (θ − θc), v = z − zc.
  double centreTheta = 0.0;
  double centreZ = 0.0;
  double chartRadius = 0.0;
  fem::SurfaceMesh surface;     ///< quadrilaterals on the skin, in the chart
  fem::ContinuumMesh continuum; ///< 20-node bricks from the skin to the bone, no sutures
  fem::MaterialTable materials; ///< by layer
  /// Quadrilaterals of the grid left out because the skin map has no skin
  /// under a corner or an edge's middle (a hole in the scan: nostrils, the
  /// eyes' shadow on a surface scan).
  int quadsWithoutSkin = 0;
};

/// @brief Meshes the face (thesis §5.3 with the mesher of §4.5.2): a grid of
/// quadrilaterals of about elementSize over faceRegion() in the skin chart,
/// extruded to the bone in layerCount layers of 20-node bricks. No sutures;
/// the deepest nodes are fixed (the bone, §4.5); the rim is free.
/// @throws std::invalid_argument for missing landmarks, bad options, or
/// when the scan leaves too little skin to mesh.
FaceMesh meshFace(const seg::RangeMap& skin, const seg::RangeMap& bone, const std::vector<seg::Landmark>& landmarks,
                  const FaceModelOptions& options = {});

} // namespace caps::expression
