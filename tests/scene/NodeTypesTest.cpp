// Each node type: setters/getters, JSON fields and bulk file round trips.

#include <gtest/gtest.h>
#include <vtkUnsignedCharArray.h>

#include <cmath>
#include <limits>

#include "SceneTestUtils.h"
#include "scene/FeMeshNode.h"
#include "scene/LabelMapNode.h"
#include "scene/LandmarksNode.h"
#include "scene/PlanNode.h"
#include "scene/RangeMapNode.h"
#include "scene/Scene.h"
#include "scene/SceneBundle.h"
#include "scene/SceneError.h"
#include "scene/SnapshotNode.h"
#include "scene/SolutionNode.h"
#include "scene/SurfaceNode.h"
#include "scene/VolumeNode.h"

namespace caps {
namespace {

using test::TempDir;

// Copies small fields through JSON and bulk data through a file into a fresh node.
template <class T> std::unique_ptr<T> roundTrip(const T& node, const std::filesystem::path& dir)
{
  auto copy = std::make_unique<T>();
  copy->fromJson(nlohmann::json::parse(node.toJson().dump()));
  const std::string ext = node.bulkFileExtension();
  if (!ext.empty())
  {
    const auto file = dir / (std::string("bulk") + ext);
    node.writeBulk(file);
    copy->readBulk(file);
  }
  return copy;
}

TEST(NodeTypes, TypeNamesRoundTrip)
{
  for (NodeType t : {NodeType::Volume, NodeType::LabelMap, NodeType::Surface, NodeType::RangeMap, NodeType::Plan,
                     NodeType::FeMesh, NodeType::Solution, NodeType::Snapshot})
  {
    EXPECT_EQ(nodeTypeFromString(nodeTypeToString(t)), t);
    EXPECT_EQ(Node::create(t)->type(), t);
  }
  EXPECT_FALSE(nodeTypeFromString("Hologram").has_value());
}

class VolumeScalarTypes : public ::testing::TestWithParam<int>
{};

TEST_P(VolumeScalarTypes, RoundTripKeepsVoxelsGeometryAndDirection)
{
  TempDir tmp;
  VolumeNode v;
  v.setName("CT head");
  v.setImage(test::makeImage(GetParam()));
  v.setMetadata({{"PatientName", "Doe^Jane"}, {"StudyDate", "19910517"}, {"SeriesDescription", "Head 1.25mm"}});
  v.setSourcePath("/data/ct/series1");
  v.setWindowLevel(80, 40);
  EXPECT_EQ(v.bulkFileExtension(), ".nrrd");
  auto copy = roundTrip(v, tmp.path());
  EXPECT_EQ(copy->name(), "CT head");
  EXPECT_EQ(copy->metadata(), v.metadata());
  EXPECT_EQ(copy->sourcePath(), "/data/ct/series1");
  EXPECT_EQ(copy->window(), 80);
  EXPECT_EQ(copy->level(), 40);
  test::expectSameImage(v.image(), copy->image());
}

INSTANTIATE_TEST_SUITE_P(AllTypes, VolumeScalarTypes,
                         ::testing::Values(VTK_SHORT, VTK_UNSIGNED_SHORT, VTK_UNSIGNED_CHAR, VTK_INT, VTK_FLOAT,
                                           VTK_DOUBLE));

TEST(NodeTypes, VolumeWithoutImageHasNoBulkFile)
{
  VolumeNode v;
  EXPECT_EQ(v.bulkFileExtension(), "");
}

TEST(NodeTypes, LabelMapRoundTripKeepsTableAndGeometry)
{
  TempDir tmp;
  LabelMapNode l;
  l.setImage(test::makeImage(VTK_UNSIGNED_CHAR));
  l.setReferenceVolumeId("Volume1");
  l.setLabels({{1, {"skin", {1.0, 0.8, 0.7}}}, {2, {"bone", {0.95, 0.95, 0.9}}}});
  l.setLabel(3, {"cartilage", {0.2, 0.4, 0.9}});
  EXPECT_EQ(l.labels().size(), 3u);
  EXPECT_FALSE(l.thresholds().has_value());
  EXPECT_FALSE(roundTrip(l, tmp.path())->thresholds().has_value());
  l.setThresholds(LabelMapNode::Thresholds{-312.5, 275.0});
  auto copy = roundTrip(l, tmp.path());
  EXPECT_EQ(copy->referenceVolumeId(), "Volume1");
  EXPECT_EQ(copy->labels(), l.labels());
  ASSERT_TRUE(copy->thresholds().has_value());
  EXPECT_EQ(*copy->thresholds(), (LabelMapNode::Thresholds{-312.5, 275.0}));
  test::expectSameImage(l.image(), copy->image());
}

TEST(NodeTypes, LabelMapRefusesThresholdsWithTheBoneBelowTheSkin)
{
  LabelMapNode l;
  nlohmann::json j = l.toJson();
  j["thresholdsHu"] = {{"skin", 300.0}, {"bone", -400.0}};
  LabelMapNode read;
  try
  {
    read.fromJson(j);
    FAIL() << "swapped thresholds were accepted";
  }
  catch (const SceneError& e)
  {
    EXPECT_NE(std::string(e.what()).find("segment again"), std::string::npos) << e.what();
  }
}

TEST(NodeTypes, LabelMapRejectsNonByteImages)
{
  LabelMapNode l;
  EXPECT_THROW(l.setImage(test::makeImage(VTK_SHORT)), SceneError);
  TempDir tmp;
  VolumeNode v;
  v.setImage(test::makeImage(VTK_FLOAT));
  v.writeBulk(tmp.path() / "f.nrrd");
  EXPECT_THROW(l.readBulk(tmp.path() / "f.nrrd"), SceneError);
}

TEST(NodeTypes, SurfaceRoundTripKeepsPointsCellsAndArrays)
{
  TempDir tmp;
  SurfaceNode s;
  s.setPolyData(test::makeSurface());
  s.setColor({0.1, 0.2, 0.3});
  s.setOpacity(0.5);
  s.setVisible(false);
  s.setSourceLabelMapId("LabelMap2");
  EXPECT_EQ(s.bulkFileExtension(), ".vtu");
  auto copy = roundTrip(s, tmp.path());
  EXPECT_EQ(copy->color(), (std::array<double, 3>{0.1, 0.2, 0.3}));
  EXPECT_EQ(copy->opacity(), 0.5);
  EXPECT_FALSE(copy->visible());
  EXPECT_EQ(copy->sourceLabelMapId(), "LabelMap2");
  vtkPolyData* a = s.polyData();
  vtkPolyData* b = copy->polyData();
  ASSERT_TRUE(b);
  ASSERT_EQ(b->GetNumberOfPoints(), 4);
  for (vtkIdType i = 0; i < 4; ++i)
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(a->GetPoint(i)[c], b->GetPoint(i)[c]);
  EXPECT_EQ(b->GetNumberOfPolys(), 2);
  EXPECT_EQ(b->GetNumberOfLines(), 1);
  auto* thickness = b->GetPointData()->GetArray("thickness");
  ASSERT_TRUE(thickness);
  EXPECT_EQ(thickness->GetTuple1(3), 5.0);
  auto* region = b->GetCellData()->GetArray("region");
  ASSERT_TRUE(region);
  for (vtkIdType c = 0; c < 3; ++c)
    EXPECT_EQ(region->GetTuple1(c), a->GetCellData()->GetArray("region")->GetTuple1(c));
  vtkIdType npts;
  const vtkIdType* pts;
  b->GetCellPoints(2, npts, pts); // second triangle (after the line)
  ASSERT_EQ(npts, 3);
  EXPECT_EQ(pts[2], 3);
}

TEST(NodeTypes, RangeMapRoundTripKeepsNaNAndFrame)
{
  TempDir tmp;
  RangeMapNode r;
  Eigen::MatrixXf values(36, 7);
  for (int i = 0; i < 36; ++i)
    for (int j = 0; j < 7; ++j)
      values(i, j) = 80.0f + static_cast<float>(i) * 0.25f + static_cast<float>(j);
  values(3, 4) = std::numeric_limits<float>::quiet_NaN();
  values(35, 0) = std::numeric_limits<float>::quiet_NaN();
  r.setValues(values);
  r.setRole("bone");
  r.setAxis({1.0, -2.0, 3.0}, {0.0, 0.0, 2.0});
  r.setZRange(-60.0, 90.0);
  r.setSourceVolumeId("Volume2");
  r.setSourceLabelMapId("LabelMap3");
  r.setSkinMapId("RangeMap7");
  EXPECT_EQ(r.axisDirection(), Eigen::Vector3d::UnitZ()); // normalised
  EXPECT_DOUBLE_EQ(r.thetaAt(0), -M_PI);
  EXPECT_DOUBLE_EQ(r.thetaAt(9), -M_PI / 2); // front of the face
  EXPECT_DOUBLE_EQ(r.zAt(6), 90.0);
  auto copy = roundTrip(r, tmp.path());
  EXPECT_EQ(copy->role(), "bone");
  EXPECT_EQ(copy->axisOrigin(), Eigen::Vector3d(1.0, -2.0, 3.0));
  EXPECT_EQ(copy->axisDirection(), Eigen::Vector3d::UnitZ());
  EXPECT_EQ(copy->zMin(), -60.0);
  EXPECT_EQ(copy->zMax(), 90.0);
  EXPECT_EQ(copy->sourceVolumeId(), "Volume2");
  EXPECT_EQ(copy->sourceLabelMapId(), "LabelMap3");
  EXPECT_EQ(copy->skinMapId(), "RangeMap7");
  ASSERT_EQ(copy->values().rows(), 36);
  ASSERT_EQ(copy->values().cols(), 7);
  EXPECT_TRUE(std::isnan(copy->values()(3, 4)));
  EXPECT_TRUE(std::isnan(copy->values()(35, 0)));
  EXPECT_EQ(copy->values()(2, 4), values(2, 4));
  EXPECT_EQ(copy->values().unaryExpr([](float v) { return std::isnan(v) ? -1.0f : v; }),
            values.unaryExpr([](float v) { return std::isnan(v) ? -1.0f : v; }));
}

TEST(NodeTypes, PlanJsonRoundTripAndNoBulk)
{
  PlanNode p;
  p.setProcedure("z-plasty");
  p.setParameters({{"angle", 1.047}, {"limbLength", 15.0}});
  p.setParameter("depth", 4.5);
  p.setCutPath({{-0.5, 0.1}, {0.0, 0.2}, {0.5, -0.1}});
  p.setCutPoint(1, {0.05, 0.25});
  EXPECT_THROW(p.setCutPoint(7, {0, 0}), SceneError);
  p.setSutures({{0, 1, 2, 3}, {4, 5, 6, 7}});
  p.setNotes("left cheek");
  p.setRangeMapId("RangeMap1");
  p.setGenerator("z");
  p.setUnderminingBand(12.5);
  p.setCutDepth("fascia");
  EXPECT_THROW(p.setCutDepth("muscle"), SceneError);
  p.setCentre({-1.5707963267948966, -42.25});
  p.setBorderOffsets({{0, 0}, {0.5, -1.25}, {0, 0}, {-0.5, 1.25}});
  EXPECT_EQ(p.bulkFileExtension(), "");
  PlanNode q;
  q.fromJson(nlohmann::json::parse(p.toJson().dump()));
  EXPECT_EQ(q.procedure(), "z-plasty");
  EXPECT_EQ(q.parameters(), p.parameters());
  EXPECT_EQ(q.cutPath(), p.cutPath());
  EXPECT_EQ(q.cutPath()[1], Eigen::Vector2d(0.05, 0.25));
  EXPECT_EQ(q.sutures(), p.sutures());
  EXPECT_EQ(q.notes(), "left cheek");
  EXPECT_EQ(q.rangeMapId(), "RangeMap1");
  EXPECT_EQ(q.generator(), "z");
  EXPECT_EQ(q.underminingBand(), 12.5);
  EXPECT_EQ(q.cutDepth(), "fascia");
  EXPECT_EQ(q.centre(), p.centre()); // exact: JSON keeps doubles to the last bit
  EXPECT_EQ(q.borderOffsets(), p.borderOffsets());
  EXPECT_EQ(q.toJson(), p.toJson());
  EXPECT_THROW(q.fromJson({{"centre", {1.0}}}), SceneError);
  EXPECT_THROW(q.fromJson({{"borderOffsets", {{1.0, "x"}}}}), SceneError);
  EXPECT_THROW(q.fromJson({{"underminingBand", -3.0}}), SceneError);
  EXPECT_THROW(q.fromJson({{"cutDepth", "muscle"}}), SceneError);
}

// A missing or null key keeps the field (the JsonFields rule) for lists too,
// and numbers that do not fit an int throw SceneError instead of being cast.
// Landmarks and the distances measured with the ruler come back as they
// were; a scene saved before the ruler (no "distances") keeps its landmarks;
// a position that is not a number is refused with the measurement's name.
TEST(NodeTypes, LandmarksAndDistancesRoundTrip)
{
  TempDir tmp;
  LandmarksNode n;
  n.setLandmarks({{"nasion", {1.5, -2.25, 700.125}}});
  n.addDistance({"Ruler 1", {0.0, 0.0, 0.0}, {3.0, 4.0, 12.0}});
  EXPECT_DOUBLE_EQ(n.distances().front().length(), 13.0);
  auto copy = roundTrip(n, tmp.path());
  EXPECT_EQ(copy->landmarks(), n.landmarks());
  EXPECT_EQ(copy->distances(), n.distances());

  LandmarksNode old;
  old.fromJson({{"landmarks", {{{"name", "pogonion"}, {"position", {1, 2, 3}}}}}});
  ASSERT_EQ(old.landmarks().size(), 1u);
  EXPECT_TRUE(old.distances().empty());
  try
  {
    old.fromJson(
      {{"distances",
        {{{"name", "Ruler 2"}, {"from", {0, 0, 0}}, {"to", {0.0, std::numeric_limits<double>::infinity(), 0.0}}}}}});
    ADD_FAILURE() << "a distance with a bad end was read";
  }
  catch (const std::exception& e)
  {
    EXPECT_NE(std::string(e.what()).find("Ruler 2"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(old.distances().empty());
  old.removeDistance(3); // none: nothing happens
}

TEST(NodeTypes, NullKeepsListsAndOutOfRangeNumbersThrow)
{
  LabelMapNode l;
  l.setLabels({{1, {"skin", {1.0, 0.8, 0.7}}}});
  l.fromJson({{"labels", nullptr}});
  EXPECT_EQ(l.labels().size(), 1u);
  for (const auto& value : {nlohmann::json(1e20), nlohmann::json(2.5), nlohmann::json(4294967296LL),
                            nlohmann::json(18446744073709551615ULL), nlohmann::json("1")})
  {
    nlohmann::json j{{"labels", {{{"value", value}, {"name", "x"}, {"color", {0, 0, 0}}}}}};
    EXPECT_THROW(l.fromJson(j), std::exception) << value;
  }
  EXPECT_THROW(l.fromJson({{"labels", {{"value", 1}}}}), std::exception); // not a list of labels
  EXPECT_EQ(l.labels().size(), 1u);
  l.fromJson({{"labels", {{{"value", 7.0}, {"name", "x"}, {"color", {0, 0, 0}}}}}});
  ASSERT_EQ(l.labels().count(7), 1u);

  PlanNode p;
  p.setCutPath({{0.0, 0.1}});
  p.setSutures({{0, 1, 2, 3}});
  p.fromJson({{"cutPath", nullptr}, {"sutures", nullptr}});
  EXPECT_EQ(p.cutPath().size(), 1u);
  EXPECT_EQ(p.sutures().size(), 1u);
  EXPECT_THROW(p.fromJson({{"sutures", {{0, 1, 2, 1e20}}}}), SceneError);
  EXPECT_THROW(p.fromJson({{"sutures", {{0, 1, 2}}}}), SceneError);
  EXPECT_EQ(p.sutures(), (std::vector<std::array<int, 4>>{{0, 1, 2, 3}}));
  p.fromJson({{"sutures", {{-4, 5, 6, 2147483647}}}});
  EXPECT_EQ(p.sutures(), (std::vector<std::array<int, 4>>{{-4, 5, 6, 2147483647}}));
}

TEST(NodeTypes, FeMeshAndSolutionRoundTripKeepArrays)
{
  TempDir tmp;
  FeMeshNode m;
  m.setMesh(test::makeQuadraticHexMesh());
  m.setPlanId("Plan1");
  auto mc = roundTrip(m, tmp.path());
  EXPECT_EQ(mc->planId(), "Plan1");
  ASSERT_TRUE(mc->mesh());
  EXPECT_EQ(mc->mesh()->GetNumberOfPoints(), 20);
  EXPECT_EQ(mc->mesh()->GetCellType(0), VTK_QUADRATIC_HEXAHEDRON);
  EXPECT_EQ(mc->mesh()->GetCellData()->GetArray("region")->GetTuple1(0), 3);

  SolutionNode s;
  s.setMeshId("FeMesh1");
  s.setResult(test::makeQuadraticHexMesh());
  s.setLoadCase("sutures+gravity");
  auto sc = roundTrip(s, tmp.path());
  EXPECT_EQ(sc->meshId(), "FeMesh1");
  EXPECT_EQ(sc->loadCase(), "sutures+gravity");
  auto* disp = sc->result()->GetPointData()->GetArray("displacement");
  ASSERT_TRUE(disp);
  EXPECT_EQ(disp->GetNumberOfComponents(), 3);
  EXPECT_DOUBLE_EQ(disp->GetComponent(19, 1), -0.2 * 19);
  auto* stress = sc->result()->GetPointData()->GetArray("stress");
  ASSERT_TRUE(stress);
  EXPECT_EQ(stress->GetNumberOfComponents(), 6);
  EXPECT_DOUBLE_EQ(stress->GetComponent(4, 5), 10.0);
}

TEST(NodeTypes, SnapshotRoundTripWithAndWithoutImage)
{
  TempDir tmp;
  SnapshotNode s;
  s.setCaption("Before: frontal");
  s.setCamera({{10, -400, 20}, {0, 0, 15}, {0, 0, 1}, 25.0});
  EXPECT_EQ(s.bulkFileExtension(), ""); // no image: no file
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(8, 6, 1);
  image->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
  auto* px = static_cast<unsigned char*>(image->GetScalarPointer());
  for (int i = 0; i < 8 * 6 * 3; ++i)
    px[i] = static_cast<unsigned char>(i * 5);
  s.setImage(image);
  EXPECT_EQ(s.bulkFileExtension(), ".png");
  auto copy = roundTrip(s, tmp.path());
  EXPECT_EQ(copy->caption(), "Before: frontal");
  EXPECT_EQ(copy->camera(), s.camera());
  ASSERT_TRUE(copy->image());
  EXPECT_EQ(copy->image()->GetNumberOfScalarComponents(), 3);
  EXPECT_EQ(0, std::memcmp(copy->image()->GetScalarPointer(), px, 8 * 6 * 3));
}

TEST(NodeTypes, AllTypesSurviveABundle)
{
  TempDir tmp;
  Scene scene;
  auto* v = scene.add<VolumeNode>();
  v->setImage(test::makeImage(VTK_SHORT));
  scene.add<LabelMapNode>()->setImage(test::makeImage(VTK_UNSIGNED_CHAR));
  scene.add<SurfaceNode>()->setPolyData(test::makeSurface());
  scene.add<RangeMapNode>()->setValues(Eigen::MatrixXf::Constant(4, 3, 1.5f));
  scene.add<PlanNode>()->setProcedure("elliptical-excision");
  scene.add<FeMeshNode>()->setMesh(test::makeQuadraticHexMesh());
  scene.add<SolutionNode>()->setResult(test::makeQuadraticHexMesh());
  scene.add<SnapshotNode>()->setCaption("no picture");
  saveSceneBundle(scene, tmp.path() / "all.caps");
  Scene loaded;
  loadSceneBundle(loaded, tmp.path() / "all.caps");
  ASSERT_EQ(loaded.size(), scene.size());
  for (std::size_t i = 0; i < scene.size(); ++i)
  {
    EXPECT_EQ(loaded.nodes()[i]->id(), scene.nodes()[i]->id());
    EXPECT_EQ(loaded.nodes()[i]->toJson(), scene.nodes()[i]->toJson());
  }
  test::expectSameImage(v->image(), loaded.nodeAs<VolumeNode>("Volume1")->image());
  EXPECT_TRUE(std::filesystem::exists(tmp.path() / "all.caps" / "Volume1.nrrd"));
  EXPECT_TRUE(std::filesystem::exists(tmp.path() / "all.caps" / "Surface1.vtu"));
  EXPECT_FALSE(std::filesystem::exists(tmp.path() / "all.caps" / "Snapshot1.png"));
}

} // namespace
} // namespace caps
