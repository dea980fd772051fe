// Procedure files: loading, validation errors with file and line, parameter
// ranges, and placement on the skin (across the θ = ±π seam too).

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>

#include "AnalyticSkins.h"
#include "TestPaths.h"
#include "planning/SkinMeasurements.h"

using namespace caps;
using namespace caps::planning;
namespace fs = std::filesystem;

namespace {

const char* kGoodZ = R"(# a Z-plasty written by a test
procedure = test-z
title = Test Z
generator = z
param central_length = 20 mm [5, 80] central limb
param limb_angle = 60 deg [30, 90] limb angle
param axis_angle = 0 deg [-180, 180] axis
suture = ((5,0),(5,4))
suture = ((2,1),(2,3))
suture = ((0,1),(3,4))
)";

fs::path writeFile(const fs::path& folder, const std::string& name, const std::string& text)
{
  const fs::path file = folder / name;
  std::ofstream(file) << text;
  return file;
}

std::string replaced(std::string text, const std::string& from, const std::string& to)
{
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

/// The error loading text gives, or "" when it loads.
std::string loadError(const std::string& text)
{
  const fs::path file = writeFile(test::scratchFolder(), "broken.procedure", text);
  try
  {
    ProcedureTemplate::load(file);
  }
  catch (const ProcedureFileError& e)
  {
    return e.what();
  }
  return "";
}

} // namespace

TEST(ProcedureFile, GoodFileLoads)
{
  const fs::path file = writeFile(test::scratchFolder(), "z.procedure", kGoodZ);
  const ProcedureTemplate t = ProcedureTemplate::load(file);
  EXPECT_EQ(t.id(), "test-z");
  EXPECT_EQ(t.title(), "Test Z");
  EXPECT_EQ(t.pathPoints(), 4);
  ASSERT_NE(t.parameter("limb_angle"), nullptr);
  EXPECT_NEAR(t.parameter("limb_angle")->defaultValue, 60.0 * test::degree, 1e-15); // radians in the API
  EXPECT_NEAR(t.parameter("limb_angle")->maximum, 90.0 * test::degree, 1e-15);
  EXPECT_EQ(t.parameter("limb_angle")->label, "limb angle");
  EXPECT_EQ(t.parameter("limb_angle")->line, 6);
}

TEST(ProcedureFile, SutureOnAnEdgeThatDoesNotExistNamesFileAndLine)
{
  const std::string e = loadError(replaced(kGoodZ, "((0,1),(3,4))", "((0,1),(3,5))"));
  EXPECT_NE(e.find("broken.procedure:10: "), std::string::npos) << e;
  EXPECT_NE(e.find("(3,5) is not a border edge"), std::string::npos) << e;
}

TEST(ProcedureFile, EdgeSewnTwiceNamesBothSutures)
{
  const std::string e = loadError(replaced(kGoodZ, "((0,1),(3,4))", "((1,0),(3,4))\nsuture = (2,1) (0,1)"));
  EXPECT_NE(e.find("broken.procedure:11: "), std::string::npos) << e;
  EXPECT_NE(e.find("already sewn by suture 2"), std::string::npos) << e;
}

TEST(ProcedureFile, BadParameterRangesAreRefused)
{
  std::string e = loadError(replaced(kGoodZ, "60 deg [30, 90]", "95 deg [30, 90]"));
  EXPECT_NE(e.find("broken.procedure:6: "), std::string::npos) << e;
  EXPECT_NE(e.find("default 95 is outside its range [30, 90]"), std::string::npos) << e;
  e = loadError(replaced(kGoodZ, "20 mm [5, 80]", "20 mm [80, 5]"));
  EXPECT_NE(e.find(":5: "), std::string::npos) << e;
  EXPECT_NE(e.find("is empty"), std::string::npos) << e;
  e = loadError(replaced(kGoodZ, "20 mm [5, 80]", "20 mm [-5, 80]"));
  EXPECT_NE(e.find("must be positive"), std::string::npos) << e;
  e = loadError(replaced(kGoodZ, "20 mm [5, 80]", "20 [5, 80]"));
  EXPECT_NE(e.find("expected 'DEFAULT UNIT [MIN, MAX] label'"), std::string::npos) << e;
  e = loadError(replaced(kGoodZ, "60 deg [30, 90]", "60 mm [30, 90]"));
  EXPECT_NE(e.find("'limb_angle' is measured in deg, not mm"), std::string::npos) << e;
}

TEST(ProcedureFile, TheDefaultUnderminingGrowsWithTheProcedure)
{
  const fs::path file = writeFile(
    test::scratchFolder(), "z-undermined.procedure",
    replaced(kGoodZ, "suture = ((5,0),(5,4))", "undermining = band 0.5 central_length + 2 mm\nsuture = ((5,0),(5,4))"));
  const ProcedureTemplate t = ProcedureTemplate::load(file);
  EXPECT_EQ(t.undermining().parameter, "central_length");
  const auto skin = test::cylinderSkin(80.0);
  EXPECT_DOUBLE_EQ(t.place(skin, {-test::pi / 2, 20.0}).underminingBand(), 0.5 * 20.0 + 2.0);
  EXPECT_DOUBLE_EQ(t.place(skin, {-test::pi / 2, 20.0}, {{"central_length", 30.0}}).underminingBand(), 17.0);
  // Without the key the procedure undermines nothing.
  const fs::path plain = writeFile(test::scratchFolder(), "z.procedure", kGoodZ);
  EXPECT_EQ(ProcedureTemplate::load(plain).place(skin, {-test::pi / 2, 20.0}).underminingBand(), 0.0);

  std::string e =
    loadError(replaced(kGoodZ, "suture = ((5,0),(5,4))", "undermining = band 0.5 limb_angle\nsuture = ((5,0),(5,4))"));
  EXPECT_NE(e.find(":8: the undermining band is scaled by 'limb_angle', which is not a length"), std::string::npos)
    << e;
  e = loadError(replaced(kGoodZ, "suture = ((5,0),(5,4))", "undermining = 10\nsuture = ((5,0),(5,4))"));
  EXPECT_NE(e.find(":8: expected 'undermining = band W mm'"), std::string::npos) << e;
  e = loadError(
    replaced(kGoodZ, "suture = ((5,0),(5,4))", "undermining = band 3 central_length\nsuture = ((5,0),(5,4))"));
  EXPECT_NE(e.find("60.000000 mm wide at the default parameters"), std::string::npos) << e;
}

TEST(ProcedureFile, TheDepthSaysWhereTheFlapsAreRaised)
{
  const auto skin = test::cylinderSkin(80.0);
  const fs::path plain = writeFile(test::scratchFolder(), "z.procedure", kGoodZ);
  EXPECT_EQ(ProcedureTemplate::load(plain).place(skin, {-test::pi / 2, 20.0}).cutDepth(), CutDepth::Bone)
    << "without the key: the thesis's full thickness";
  const fs::path fascia =
    writeFile(test::scratchFolder(), "z-fascia.procedure",
              replaced(kGoodZ, "suture = ((5,0),(5,4))", "depth = fascia\nsuture = ((5,0),(5,4))"));
  EXPECT_EQ(ProcedureTemplate::load(fascia).place(skin, {-test::pi / 2, 20.0}).cutDepth(), CutDepth::Fascia);
  EXPECT_EQ(layersCutTo(CutDepth::Fascia, 3), 2);
  EXPECT_EQ(layersCutTo(CutDepth::Fascia, 1), 1);
  EXPECT_EQ(layersCutTo(CutDepth::Bone, 4), 4);
  const std::string e = loadError(replaced(kGoodZ, "suture = ((5,0),(5,4))", "depth = muscle\nsuture = ((5,0),(5,4))"));
  EXPECT_NE(e.find(":8: expected 'depth = fascia'"), std::string::npos) << e;
}

TEST(ProcedureFile, EveryShippedProcedureStatesItsUndermining)
{
  // Surgeons undermine every one of these closures (data/procedures/README.md
  // gives each band and why): a few mm to a few cm, never none.
  const auto skin = test::cylinderSkin(80.0);
  for (const auto& t : test::shippedProcedures().procedures())
  {
    SCOPED_TRACE(t.id());
    const IncisionPlan plan = t.place(skin, {-test::pi / 2, 20.0});
    EXPECT_GE(plan.underminingBand(), 3.0);
    EXPECT_LE(plan.underminingBand(), 25.0);
    EXPECT_EQ(plan.cutDepth(), CutDepth::Fascia) << "facial flaps are raised on the fascia";
  }
}

TEST(ProcedureFile, TopologyMistakesAreRefused)
{
  std::string e = loadError(replaced(kGoodZ, "generator = z", "generator = w-plasty"));
  EXPECT_NE(e.find(":4: unknown generator 'w-plasty'; known: ellipse, z"), std::string::npos) << e;
  e = loadError(replaced(kGoodZ, "param limb_angle = 60 deg [30, 90] limb angle\n", ""));
  EXPECT_NE(e.find(":4: the 'z' generator needs parameter 'limb_angle'"), std::string::npos) << e;
  e = loadError(replaced(kGoodZ, "title = Test Z", "title = Test Z\nparam width = 3 mm [1, 9] extra"));
  EXPECT_NE(e.find(":4: the 'z' generator has no parameter 'width'"), std::string::npos) << e;
  e = loadError(replaced(kGoodZ, "title = Test Z", "title = Test Z\npoints = 5"));
  EXPECT_NE(e.find("cuts 4 points, not 5"), std::string::npos) << e;
  e = loadError(replaced(kGoodZ, "procedure = test-z\n", ""));
  EXPECT_NE(e.find("broken.procedure: 'procedure = ...' is missing"), std::string::npos) << e;
  e = loadError(replaced(kGoodZ, "title = Test Z", "tittle = Test Z"));
  EXPECT_NE(e.find(":3: unknown key 'tittle'"), std::string::npos) << e;
  e = loadError(replaced(kGoodZ, "suture = ((0,1),(3,4))", "suture = (0,1) and (3,4)"));
  EXPECT_NE(e.find(":10: expected a pair of border edges"), std::string::npos) << e;
  // Folding (0,1) onto (2,3) would pull p1 onto p2.
  e = loadError(replaced(kGoodZ, "suture = ((0,1),(3,4))", "suture = ((0,1),(2,3))"));
  EXPECT_NE(e.find(":10: "), std::string::npos) << e;
}

TEST(ProcedureFile, ZipWritesTheThesisSimpleExcision)
{
  const fs::path file = writeFile(test::scratchFolder(), "e.procedure", R"(procedure = e4
generator = ellipse
points = 4
param length = 20 mm [4, 100] length
param width = 6 mm [1, 40] width
param axis_angle = 0 deg [-180, 180] axis
zip = 0 3
)");
  const ProcedureTemplate t = ProcedureTemplate::load(file);
  const std::vector<SutureEdges> thesis = {{{0, 1}, {0, 5}}, {{1, 2}, {5, 4}}, {{2, 3}, {4, 3}}};
  EXPECT_EQ(t.writtenSutures(), thesis);
}

TEST(ProcedureLibrary, ABadFileIsLeftOutAndReported)
{
  const fs::path folder = test::scratchFolder();
  writeFile(folder, "a.procedure", kGoodZ);
  writeFile(folder, "b.procedure", replaced(kGoodZ, "((0,1),(3,4))", "((0,1),(3,5))"));
  writeFile(folder, "c.procedure", kGoodZ); // same id again
  writeFile(folder, "notes.txt", "not a procedure");
  const ProcedureLibrary library = ProcedureLibrary::load(folder);
  ASSERT_EQ(library.procedures().size(), 1u);
  EXPECT_EQ(library.procedures()[0].file().filename(), "a.procedure");
  ASSERT_EQ(library.errors().size(), 2u);
  EXPECT_NE(library.errors()[0].find("b.procedure:10:"), std::string::npos) << library.errors()[0];
  EXPECT_NE(library.errors()[1].find("'test-z' is already defined by a.procedure"), std::string::npos)
    << library.errors()[1];
  EXPECT_THROW(ProcedureLibrary::load(folder / "missing"), std::runtime_error);
}

TEST(ProcedureLibrary, DefaultFolderFollowsCapsDataDir)
{
  ::setenv("CAPS_DATA_DIR", CAPS_TEST_DATA_DIR, 1);
  EXPECT_EQ(defaultProceduresFolder(), test::proceduresFolder());
  ::unsetenv("CAPS_DATA_DIR");
  EXPECT_TRUE(fs::is_directory(defaultProceduresFolder())); // the source tree's data/procedures
}

TEST(ProcedurePlacement, ValuesOutsideTheirRangeAreRefusedInDegrees)
{
  const auto* z = test::shippedProcedures().find("z-plasty");
  ASSERT_NE(z, nullptr);
  try
  {
    z->resolveValues({{"limb_angle", 95.0 * test::degree}});
    FAIL() << "accepted 95°";
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find("limb_angle = 95° is outside its range 30° to 90°"), std::string::npos)
      << e.what();
  }
  EXPECT_THROW(z->resolveValues({{"limb_length", 10.0}}), std::invalid_argument);
  const auto values = z->resolveValues({{"central_length", 12.0}});
  EXPECT_EQ(values.at("central_length"), 12.0);
  EXPECT_NEAR(values.at("limb_angle"), 60.0 * test::degree, 1e-15);
}

TEST(ProcedurePlacement, ZPlastyAcrossTheSeamIsOnePieceInTheChart)
{
  const double radius = 80.0;
  const auto skin = test::cylinderSkin(radius);
  const auto* z = test::shippedProcedures().find("z-plasty");
  ASSERT_NE(z, nullptr);
  // Centred 0.1 mm before the seam at θ = π, central limb around the head.
  const SkinPoint at{test::pi - 0.1 / radius, 5.0};
  const IncisionPlan plan = z->place(skin, at, {{"central_length", 20.0}});
  EXPECT_EQ(plan.procedure(), "z-plasty");
  const SkinChart chart = plan.chart(skin);
  const auto path = plan.chartPath(chart);
  // The chart shape is the Z of the procedure's own frame, unbroken.
  const ProcedureCut local = z->cut(z->resolveValues({{"central_length", 20.0}}));
  for (size_t i = 0; i < path.size(); ++i)
    EXPECT_NEAR((path[i] - local.path[i]).norm(), 0.0, 1e-9) << i;
  // ...while its points lie on both sides of the seam in normalised θ.
  EXPECT_GT(plan.cutPath()[1].x(), 0.9);  // p1 at θ below π
  EXPECT_LT(plan.cutPath()[2].x(), -0.9); // p2 wrapped to θ above -π
  for (const auto& p : plan.cutPath())
  {
    EXPECT_GE(p.x(), -1.0);
    EXPECT_LT(p.x(), 1.0);
  }
  // Limbs measured on the skin stay 20 mm across the seam.
  for (const auto& limb : measurePlan(plan, skin).limbs)
    EXPECT_NEAR(limb.skin, 20.0, 1e-6) << limb.from;
}

TEST(ProcedurePlacement, AxisAngleTurnsTheProcedure)
{
  const auto skin = test::cylinderSkin(80.0);
  const auto* z = test::shippedProcedures().find("z-plasty");
  const IncisionPlan plan = z->place(skin, {0.0, 0.0}, {{"axis_angle", 90.0 * test::degree}});
  const auto path = plan.chartPath(plan.chart(skin));
  // The central limb p1 → p2 now runs superior (+z).
  EXPECT_NEAR(path[1].x(), 0.0, 1e-9);
  EXPECT_NEAR(path[2].x(), 0.0, 1e-9);
  EXPECT_NEAR(path[2].y() - path[1].y(), 20.0, 1e-9);
}

TEST(ProcedurePlacement, EveryProcedurePlacesWithItsDefaults)
{
  const auto skin = test::cylinderSkin(80.0);
  for (const auto& t : test::shippedProcedures().procedures())
  {
    SCOPED_TRACE(t.id());
    const IncisionPlan plan = t.place(skin, {-test::pi / 2, 20.0});
    EXPECT_EQ(plan.pointCount(), t.pathPoints());
    EXPECT_EQ(plan.sutures().size(), t.sutures().size());
    EXPECT_NO_THROW(checkPlan(plan, skin));
  }
}

TEST(ProcedurePlacement, CutLeavingTheScanIsRefused)
{
  const auto skin = test::cylinderSkin(80.0, -30.0, 30.0);
  const auto* z = test::shippedProcedures().find("z-plasty");
  try
  {
    z->place(skin, {0.0, 25.0}, {{"axis_angle", 90.0 * test::degree}});
    FAIL() << "a Z reaching z = 35 mm was accepted on a scan ending at 30 mm";
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find("outside the scanned region"), std::string::npos) << e.what();
  }
  EXPECT_THROW(z->place(skin, {0.0, 45.0}), std::invalid_argument); // centre off the scan
}
