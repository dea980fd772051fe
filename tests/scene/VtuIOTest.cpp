// VTU reading: damaged files throw SceneError naming the file.

#include <gtest/gtest.h>

#include "SceneTestUtils.h"
#include "scene/SceneError.h"
#include "scene/VtuIO.h"

namespace caps {
namespace {

using test::TempDir;

// A cell naming a point the file does not have: VTK reads it as it is, and
// whoever follows it later crashes.
TEST(VtuIO, CellPointIdsOutOfRangeAreRejected)
{
  TempDir tmp;
  auto grid = test::makeQuadraticHexMesh(); // 20 points
  const vtkIdType bad[3] = {0, 1, 20};
  grid->InsertNextCell(VTK_TRIANGLE, 3, bad);
  grid->GetCellData()->GetArray("region")->InsertNextTuple1(4);
  const auto file = tmp.path() / "damaged.vtu";
  VtuIO::writeGrid(grid, file);
  try
  {
    VtuIO::readGrid(file);
    ADD_FAILURE() << "no error for " << file;
  }
  catch (const SceneError& e)
  {
    EXPECT_NE(std::string(e.what()).find("damaged.vtu"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("point 20 of 20"), std::string::npos) << e.what();
  }
  EXPECT_THROW(VtuIO::readPolyData(file), SceneError);
  // The intact mesh still reads.
  VtuIO::writeGrid(test::makeQuadraticHexMesh(), file);
  EXPECT_EQ(VtuIO::readGrid(file)->GetNumberOfCells(), 1);
}

} // namespace
} // namespace caps
