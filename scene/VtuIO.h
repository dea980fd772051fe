#pragma once

#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>

#include <filesystem>

namespace caps {

/// @brief VTK XML unstructured grid (.vtu) files for meshes and surfaces.
///
/// Surfaces are stored as unstructured grids too, so every bulky mesh in a
/// bundle opens in ParaView the same way. Point and cell data arrays survive
/// the round trip. Throws SceneError naming the file on failure.
class VtuIO
{
public:
  static void writeGrid(vtkUnstructuredGrid* grid, const std::filesystem::path& file);
  static vtkSmartPointer<vtkUnstructuredGrid> readGrid(const std::filesystem::path& file);

  /// Writes the polydata's cells (verts, lines, polys, strips in that order)
  /// as an unstructured grid with the same points and arrays.
  static void writePolyData(vtkPolyData* surface, const std::filesystem::path& file);
  /// Reads a .vtu of surface cells back into polydata with the same points,
  /// point order and arrays.
  static vtkSmartPointer<vtkPolyData> readPolyData(const std::filesystem::path& file);
};

} // namespace caps
