#pragma once

// Shared helpers of the scene tests: a temporary folder per test and small
// VTK data sets with known content.

#include <gtest/gtest.h>
#include <unistd.h>
#include <vtkCellData.h>
#include <vtkDoubleArray.h>
#include <vtkFloatArray.h>
#include <vtkImageData.h>
#include <vtkIntArray.h>
#include <vtkMatrix3x3.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkCellArray.h>
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <string>

namespace caps::test {

/// A fresh folder under the system temp dir, removed at the end of the test.
class TempDir
{
public:
  TempDir()
  {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = info ? info->name() : "x";
    for (char& c : name)
      if (c == '/')
        c = '_'; // parameterised tests are named "Test/0"
    path_ = std::filesystem::temp_directory_path() / ("caps-scene-" + name + "-" + std::to_string(::getpid()));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir()
  {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  const std::filesystem::path& path() const { return path_; }

private:
  std::filesystem::path path_;
};

/// A small image of @a vtkType with a non-identity direction matrix (a
/// rotation about z by 30 degrees) and voxel values i + 10 j + 100 k.
inline vtkSmartPointer<vtkImageData> makeImage(int vtkType, int nx = 5, int ny = 4, int nz = 3)
{
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(nx, ny, nz);
  image->SetSpacing(0.5, 0.75, 2.5);
  image->SetOrigin(-12.5, 30.25, -100.0);
  const double c = std::cos(0.5235987755982988), s = std::sin(0.5235987755982988);
  const double dir[9] = {c, -s, 0, s, c, 0, 0, 0, 1};
  image->SetDirectionMatrix(dir);
  image->AllocateScalars(vtkType, 1);
  vtkDataArray* a = image->GetPointData()->GetScalars();
  for (vtkIdType i = 0; i < a->GetNumberOfTuples(); ++i)
  {
    const int x = static_cast<int>(i % nx), y = static_cast<int>((i / nx) % ny), z = static_cast<int>(i / (nx * ny));
    a->SetTuple1(i, x + 10 * y + 100 * z);
  }
  return image;
}

inline void expectSameImage(vtkImageData* a, vtkImageData* b)
{
  ASSERT_TRUE(a);
  ASSERT_TRUE(b);
  EXPECT_EQ(a->GetScalarType(), b->GetScalarType());
  int da[3], db[3];
  a->GetDimensions(da);
  b->GetDimensions(db);
  for (int i = 0; i < 3; ++i)
  {
    EXPECT_EQ(da[i], db[i]);
    EXPECT_NEAR(a->GetSpacing()[i], b->GetSpacing()[i], 1e-12);
    EXPECT_NEAR(a->GetOrigin()[i], b->GetOrigin()[i], 1e-12);
    for (int j = 0; j < 3; ++j)
      EXPECT_NEAR(a->GetDirectionMatrix()->GetElement(i, j), b->GetDirectionMatrix()->GetElement(i, j), 1e-12);
  }
  vtkDataArray* sa = a->GetPointData()->GetScalars();
  vtkDataArray* sb = b->GetPointData()->GetScalars();
  ASSERT_EQ(sa->GetNumberOfTuples(), sb->GetNumberOfTuples());
  ASSERT_EQ(sa->GetNumberOfComponents(), sb->GetNumberOfComponents());
  EXPECT_EQ(0, std::memcmp(sa->GetVoidPointer(0), sb->GetVoidPointer(0),
                           static_cast<std::size_t>(sa->GetNumberOfValues() * sa->GetDataTypeSize())));
}

/// Two triangles and a line with a point array "thickness" and a cell array "region".
inline vtkSmartPointer<vtkPolyData> makeSurface()
{
  auto points = vtkSmartPointer<vtkPoints>::New();
  points->InsertNextPoint(0, 0, 0);
  points->InsertNextPoint(1, 0, 0);
  points->InsertNextPoint(1, 1, 0);
  points->InsertNextPoint(0, 1, 0.5);
  auto polys = vtkSmartPointer<vtkCellArray>::New();
  const vtkIdType t0[3] = {0, 1, 2}, t1[3] = {0, 2, 3}, l0[2] = {1, 3};
  polys->InsertNextCell(3, t0);
  polys->InsertNextCell(3, t1);
  auto lines = vtkSmartPointer<vtkCellArray>::New();
  lines->InsertNextCell(2, l0);
  auto pd = vtkSmartPointer<vtkPolyData>::New();
  pd->SetPoints(points);
  pd->SetPolys(polys);
  pd->SetLines(lines);
  auto thickness = vtkSmartPointer<vtkFloatArray>::New();
  thickness->SetName("thickness");
  for (int i = 0; i < 4; ++i)
    thickness->InsertNextValue(2.0f + static_cast<float>(i));
  pd->GetPointData()->AddArray(thickness);
  auto region = vtkSmartPointer<vtkIntArray>::New();
  region->SetName("region");
  for (int v : {7, 10, 11})
    region->InsertNextValue(v); // line first, then the two triangles
  pd->GetCellData()->AddArray(region);
  return pd;
}

/// One 20-node hexahedron with a cell array "region", a point vector
/// "displacement" and a point tensor-ish "stress" (6 components).
inline vtkSmartPointer<vtkUnstructuredGrid> makeQuadraticHexMesh()
{
  static const double corners[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                       {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  static const int edges[12][2] = {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {4, 5}, {5, 6},
                                   {6, 7}, {7, 4}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
  auto points = vtkSmartPointer<vtkPoints>::New();
  for (const auto& c : corners)
    points->InsertNextPoint(c);
  for (const auto& e : edges)
    points->InsertNextPoint(0.5 * (corners[e[0]][0] + corners[e[1]][0]), 0.5 * (corners[e[0]][1] + corners[e[1]][1]),
                            0.5 * (corners[e[0]][2] + corners[e[1]][2]));
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  grid->SetPoints(points);
  vtkIdType ids[20];
  for (int i = 0; i < 20; ++i)
    ids[i] = i;
  grid->InsertNextCell(VTK_QUADRATIC_HEXAHEDRON, 20, ids);
  auto region = vtkSmartPointer<vtkIntArray>::New();
  region->SetName("region");
  region->InsertNextValue(3);
  grid->GetCellData()->AddArray(region);
  auto disp = vtkSmartPointer<vtkDoubleArray>::New();
  disp->SetName("displacement");
  disp->SetNumberOfComponents(3);
  for (int i = 0; i < 20; ++i)
    disp->InsertNextTuple3(0.1 * i, -0.2 * i, 0.05);
  grid->GetPointData()->AddArray(disp);
  auto stress = vtkSmartPointer<vtkDoubleArray>::New();
  stress->SetName("stress");
  stress->SetNumberOfComponents(6);
  for (int i = 0; i < 20; ++i)
  {
    double t[6] = {1.0 * i, 2.0, 3.0, 4.0, 5.0, 6.0 + i};
    stress->InsertNextTuple(t);
  }
  grid->GetPointData()->AddArray(stress);
  return grid;
}

} // namespace caps::test
