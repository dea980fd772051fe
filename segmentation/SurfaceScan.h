#pragma once
/// @file SurfaceScan.h
/// @brief Surface scans (the thesis's Cyberware input, §3.2.1, §4.2.1): a coloured
/// mesh (PLY, OBJ) unwrapped into a range map and a colour map on a cylindrical frame.

#include <string>

#include <vtkSmartPointer.h>

#include "segmentation/RangeMap.h"
#include "segmentation/SurfaceScanColourMap.h"

class vtkPolyData;

namespace caps::seg {

/// How the mesh becomes samples.
enum class SurfaceScanSampling
{
  /// Every (θ_i, z_j) sample is the outermost crossing of the ray from the
  /// axis point at z_j towards θ_i with the mesh's triangles (like the CT
  /// range map, "march outward, outermost crossing"); its colour is the
  /// barycentric blend of the triangle's vertex colours at the crossing.
  /// The map has no holes wherever the mesh covers the ray, however coarse
  /// the mesh is, and r is exact at the sample position (for a flat triangle).
  RayCast,
  /// The §3.2.7 point-list rule on the mesh vertices (rangeMapFromPoints):
  /// each bucket keeps the largest vertex r and that vertex's colour. Fast
  /// and faithful to the thesis, but a bucket with no vertex is a hole (any
  /// mesh coarser than the grid), and r is taken up to half a bucket away
  /// from the bucket centre.
  Vertices,
};

/// The result of unwrapping a surface scan.
struct SurfaceScan
{
  RangeMap range;          ///< r in mm, NaN where the ray misses the mesh (or the bucket is empty).
  ColourMap colour;        ///< RGB of the point that gave r; black where r is NaN (and if the mesh has no colours).
  bool hasColours = false; ///< The mesh carried vertex colours.
};

/// Read a surface mesh: .ply (vtkPLYReader, colours from red/green/blue
/// vertex properties) or .obj (vtkOBJReader; colours from "v x y z r g b"
/// lines, 0..1 or 0..255). Polygons are triangulated. Colours, if any, are
/// the point array "RGB" (unsigned char, 3 components) and the active scalars.
/// @throws std::runtime_error if the file is missing, not PLY/OBJ, or has no polygons.
vtkSmartPointer<vtkPolyData> readSurfaceMesh(const std::string& path);

/// Unwrap a triangle mesh (world mm, LPS) into range and colour maps on frame's grid.
/// Colours are taken from an unsigned char point array of 3 or 4 components
/// (the active scalars, else "RGB", "RGBA" or "Colors"). Non-triangle cells are ignored.
SurfaceScan surfaceScanFromMesh(const CylindricalFrame& frame, vtkPolyData* mesh,
                                SurfaceScanSampling sampling = SurfaceScanSampling::RayCast);

/// readSurfaceMesh then surfaceScanFromMesh.
SurfaceScan readSurfaceScan(const std::string& path, const CylindricalFrame& frame,
                            SurfaceScanSampling sampling = SurfaceScanSampling::RayCast);

} // namespace caps::seg
