#include "scene/VtuIO.h"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkDataArray.h>
#include <vtkIdList.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkXMLUnstructuredGridReader.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include "scene/SceneError.h"
#include "scene/VtkErrorCatcher.h"

namespace caps {

namespace {

// 0 = vert, 1 = line, 2 = poly, 3 = strip, -1 = not a surface cell.
int surfaceCategory(int cellType)
{
  switch (cellType)
  {
  case VTK_VERTEX:
  case VTK_POLY_VERTEX:
    return 0;
  case VTK_LINE:
  case VTK_POLY_LINE:
    return 1;
  case VTK_TRIANGLE:
  case VTK_QUAD:
  case VTK_POLYGON:
  case VTK_PIXEL:
    return 2;
  case VTK_TRIANGLE_STRIP:
    return 3;
  }
  return -1;
}

// VTK reads a cell's point ids as they are: a damaged file can name points
// that do not exist, which crashes whoever follows them later. Check them here.
void checkCells(vtkUnstructuredGrid* grid, const std::filesystem::path& file)
{
  vtkCellArray* cells = grid->GetCells();
  if (!cells)
    return;
  auto damaged = [&](const std::string& what) {
    return SceneError(file.string() + " is damaged (" + what + "): restore it from a backup");
  };
  vtkDataArray* offsets = cells->GetOffsetsArray();
  vtkDataArray* connectivity = cells->GetConnectivityArray();
  const auto ids = static_cast<double>(connectivity->GetNumberOfValues());
  double previous = 0;
  for (vtkIdType i = 0; i < offsets->GetNumberOfValues(); ++i)
  {
    const double o = offsets->GetComponent(i, 0);
    if ((i == 0 && o != 0) || o < previous || o > ids)
      throw damaged("invalid cell offsets");
    previous = o;
  }
  if (previous != ids)
    throw damaged("invalid cell offsets");
  if (grid->GetCellTypesArray() && grid->GetCellTypesArray()->GetNumberOfValues() != cells->GetNumberOfCells())
    throw damaged("as many cell types as cells expected");
  const vtkIdType points = grid->GetNumberOfPoints();
  for (vtkIdType i = 0; i < connectivity->GetNumberOfValues(); ++i)
  {
    const double id = connectivity->GetComponent(i, 0);
    if (!(id >= 0 && id < static_cast<double>(points)))
      throw damaged("a cell refers to point " + std::to_string(static_cast<long long>(id)) + " of " +
                    std::to_string(points) + " points");
  }
}

} // namespace

void VtuIO::writeGrid(vtkUnstructuredGrid* grid, const std::filesystem::path& file)
{
  if (!grid)
    throw SceneError("cannot write " + file.string() + ": the mesh is empty");
  auto writer = vtkSmartPointer<vtkXMLUnstructuredGridWriter>::New();
  VtkErrorCatcher errors(writer);
  writer->SetInputData(grid);
  writer->SetFileName(file.c_str());
  writer->SetDataModeToAppended();
  writer->EncodeAppendedDataOff(); // raw binary: smaller and faster than base64
  writer->SetCompressorTypeToZLib();
  if (writer->Write() != 1 || errors.failed())
    throw SceneError("could not write " + file.string() + ": check free disk space and permissions (" +
                     errors.message() + ")");
}

vtkSmartPointer<vtkUnstructuredGrid> VtuIO::readGrid(const std::filesystem::path& file)
{
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec))
    throw SceneError("cannot open " + file.string() + ": the file is missing");
  auto reader = vtkSmartPointer<vtkXMLUnstructuredGridReader>::New();
  VtkErrorCatcher errors(reader);
  reader->SetFileName(file.c_str());
  reader->Update();
  if (errors.failed() || reader->GetErrorCode() != 0 || !reader->GetOutput())
    throw SceneError(file.string() +
                     " is damaged or truncated and cannot be read as a VTU mesh: restore it from a backup (" +
                     errors.message() + ")");
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  grid->ShallowCopy(reader->GetOutput());
  checkCells(grid, file);
  return grid;
}

void VtuIO::writePolyData(vtkPolyData* surface, const std::filesystem::path& file)
{
  if (!surface)
    throw SceneError("cannot write " + file.string() + ": the surface is empty");
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  grid->SetPoints(surface->GetPoints());
  grid->GetPointData()->ShallowCopy(surface->GetPointData());
  grid->GetFieldData()->ShallowCopy(surface->GetFieldData());
  const vtkIdType n = surface->GetNumberOfCells();
  grid->Allocate(n);
  auto ids = vtkSmartPointer<vtkIdList>::New();
  for (vtkIdType c = 0; c < n; ++c)
  {
    surface->GetCellPoints(c, ids);
    grid->InsertNextCell(surface->GetCellType(c), ids);
  }
  // vtkPolyData numbers cells verts, lines, polys, strips: the same order as
  // the loop above, so cell data copies as is.
  grid->GetCellData()->ShallowCopy(surface->GetCellData());
  writeGrid(grid, file);
}

vtkSmartPointer<vtkPolyData> VtuIO::readPolyData(const std::filesystem::path& file)
{
  auto grid = readGrid(file);
  auto surface = vtkSmartPointer<vtkPolyData>::New();
  surface->SetPoints(grid->GetPoints() ? grid->GetPoints() : vtkSmartPointer<vtkPoints>::New().GetPointer());
  surface->GetPointData()->ShallowCopy(grid->GetPointData());
  surface->GetFieldData()->ShallowCopy(grid->GetFieldData());
  vtkSmartPointer<vtkCellArray> arrays[4];
  for (auto& a : arrays)
    a = vtkSmartPointer<vtkCellArray>::New();
  const vtkIdType n = grid->GetNumberOfCells();
  std::vector<vtkIdType> order[4];
  auto ids = vtkSmartPointer<vtkIdList>::New();
  for (vtkIdType c = 0; c < n; ++c)
  {
    const int cat = surfaceCategory(grid->GetCellType(c));
    if (cat < 0)
      throw SceneError(file.string() + " holds volume cells, not a surface: it is not a CAPS surface file");
    grid->GetCellPoints(c, ids);
    arrays[cat]->InsertNextCell(ids);
    order[cat].push_back(c);
  }
  surface->SetVerts(arrays[0]);
  surface->SetLines(arrays[1]);
  surface->SetPolys(arrays[2]);
  surface->SetStrips(arrays[3]);
  // Cell data follow the polydata numbering (verts, lines, polys, strips).
  vtkCellData* in = grid->GetCellData();
  vtkCellData* out = surface->GetCellData();
  out->CopyAllocate(in, n);
  vtkIdType next = 0;
  for (const auto& o : order)
    for (vtkIdType c : o)
      out->CopyData(in, c, next++);
  return surface;
}

} // namespace caps
