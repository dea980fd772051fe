// Display surfaces of simulated plans (thesis §4.7) on the cylinder phantom
// of PlanSimulationTest (skin r = 80 mm, bone r = 70 mm): range detail puts
// every vertex back on the scanned skin, the wound closes in the display
// too, a symmetric plan shows a symmetric stress field, and the polydata and
// the CT-derived skin shade carry what they claim.

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <set>
#include <tuple>

#include <gtest/gtest.h>

#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkImageData.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkShortArray.h>
#include <vtkSmartPointer.h>
#include <vtkXMLPolyDataReader.h>

#include "AnalyticSkins.h"
#include "planning/PlanDisplay.h"
#include "segmentation/SkinShade.h"

namespace caps::planning {
namespace {

using Phantom = test::CylinderPhantom;
const Phantom& phantom()
{
  return test::cylinderPhantom();
}

SimulationOptions testOptions()
{
  return test::phantomSimulationOptions();
}

/// The symmetric ellipse of PlanSimulationTest: 24 mm, 3:1, along θ at (0, 0).
const PlanPrediction& ellipse()
{
  static const PlanPrediction p = [] {
    const ProcedureTemplate* t = test::shippedProcedures().find("elliptical-excision");
    const IncisionPlan plan =
      t->place(phantom().skin, {0.0, 0.0}, {{"length", 24.0}, {"ratio", 3.0}, {"axis_angle", 0.0}});
    return simulatePlan(phantom().skin, phantom().bone, plan, testOptions());
  }();
  return p;
}

double radius(const Eigen::Vector3d& x)
{
  return std::hypot(x.x(), x.y());
}

/// Mesh nodes carrying the weight of vertex v.
std::vector<int> supportOf(const fem::DisplaySurface& s, Eigen::Index v)
{
  std::vector<int> nodes;
  for (Eigen::SparseMatrix<double>::InnerIterator it(s.interpolation(), v); it; ++it)
    nodes.push_back(s.displayNodes()[std::size_t(it.row())]);
  return nodes;
}

/// Skin nodes of the wound border: the hole loop's vertices and the mid-edge
/// nodes of its edges.
std::set<int> woundBorderNodes(const PlanPrediction& p)
{
  std::set<int> nodes;
  const int loop = p.skin.holeVertexCount;
  for (int v = 0; v < loop; ++v)
  {
    nodes.insert(p.continuum.vertexColumns[std::size_t(v)].front());
    const int e = p.continuum.edgeIndex(v, (v + 1) % loop);
    if (e >= 0)
      nodes.insert(p.continuum.edgeColumns[std::size_t(e)].front());
  }
  return nodes;
}

TEST(PlanDisplay, RangeDetailPutsEveryVertexOnTheScannedSkin)
{
  const PlanPrediction& p = ellipse();
  // One top face per surface polygon.
  EXPECT_EQ(fem::skinFaces(p.continuum).size(), p.surface.mesh.polygons.size());
  for (int n : {1, 2, 4, 8})
  {
    PlanDisplayOptions o;
    o.resolution = n;
    const PlanDisplay d = buildPlanDisplay(p, phantom().skin, nullptr, o);
    const Eigen::Matrix3Xd withDetail = d.positions(0.0);
    const Eigen::Matrix3Xd& faces = d.surface.undeformedPositions();
    double onSkin = 0.0, faceDeviation = 0.0, atNodes = 0.0;
    for (Eigen::Index v = 0; v < faces.cols(); ++v)
    {
      onSkin = std::max(onSkin, std::abs(radius(withDetail.col(v)) - 80.0));
      faceDeviation = std::max(faceDeviation, std::abs(radius(faces.col(v)) - 80.0));
      if (supportOf(d.surface, v).size() == 1) // on a node: corner and mid-edge nodes lie on the skin
        atNodes = std::max(atNodes, d.surface.rangeDetail().col(v).norm());
    }
    std::printf("[range detail, n = %d] %ld vertices, %zu polygons: quadratic faces stray up to %.3g mm from the "
                "skin (r = 80 mm), with range detail %.3g mm; detail at the nodes %.3g mm\n",
                n, long(faces.cols()), d.surface.polygons().size(), faceDeviation, onSkin, atNodes);
    EXPECT_EQ(d.verticesWithoutScan, 0);
    EXPECT_LT(onSkin, 1e-9);
    EXPECT_LT(atNodes, 1e-9);
    EXPECT_NEAR(d.largestRangeDetail, faceDeviation, 1e-9);
    if (n > 1)
    {
      EXPECT_GT(faceDeviation, 1e-7); // between the nodes the quadratic face is not the cylinder...
      EXPECT_LT(faceDeviation, 0.05); // ...but close to it
    }
    // Without range detail the surface is the faces themselves.
    o.rangeDetail = false;
    const PlanDisplay plain = buildPlanDisplay(p, phantom().skin, nullptr, o);
    EXPECT_EQ(plain.positions(0.0), faces);
  }
}

// A pit in the scan between the nodes (a nostril, the fold under the nose):
// the ray meets the skin 10 mm deeper than the element face, which the
// display does not follow beyond maxRangeDetail; with a larger limit it does.
TEST(PlanDisplay, RangeDetailDoesNotFollowPitsBetweenTheNodes)
{
  const PlanPrediction& p = ellipse();
  seg::RangeMap pitted = phantom().skin;
  const seg::CylindricalFrame& f = pitted.frame();
  // A 1.5 × 1.5 mm pit 8 mm beside the wound: smaller than an element, so no node stands in it.
  int samples = 0;
  for (int j = 0; j < f.nZ(); ++j)
    for (int i = 0; i < f.nTheta(); ++i)
    {
      const double u = 80.0 * f.indexToTheta(i), z = f.indexToZ(j);
      if (std::abs(z - 8.0) < 0.75 && std::abs(u - 0.0) < 0.75)
        pitted.at(i, j) = 70.0f, ++samples;
    }
  ASSERT_GT(samples, 0);
  PlanDisplayOptions o;
  o.resolution = 8;
  const PlanDisplay limited = buildPlanDisplay(p, pitted, nullptr, o);
  o.maxRangeDetail = 100.0;
  const PlanDisplay following = buildPlanDisplay(p, pitted, nullptr, o);
  std::printf("[pit] %d of %ld vertices over the pit left on the element face; detail up to %.2f mm with the "
              "limit, %.2f mm without\n",
              limited.verticesBeyondDetailLimit, long(limited.surface.vertexCount()), limited.largestRangeDetail,
              following.largestRangeDetail);
  EXPECT_GT(limited.verticesBeyondDetailLimit, 0);
  EXPECT_LE(limited.largestRangeDetail, 3.0);
  EXPECT_EQ(following.verticesBeyondDetailLimit, 0);
  EXPECT_GT(following.largestRangeDetail, 5.0);
}

TEST(PlanDisplay, TheDeformedSurfaceIsClosedAtTheSutures)
{
  const PlanPrediction& p = ellipse();
  const std::set<int> border = woundBorderNodes(p);
  const PlanDisplay d = buildPlanDisplay(p, phantom().skin);
  const fem::DisplaySurface& s = d.surface;
  std::vector<Eigen::Index> onBorder;
  for (Eigen::Index v = 0; v < s.vertexCount(); ++v)
  {
    const std::vector<int> support = supportOf(s, v);
    if (std::all_of(support.begin(), support.end(), [&](int n) { return border.count(n) > 0; }))
      onBorder.push_back(v);
  }
  // Each border vertex meets a vertex of the other side (apart before, together
  // after); only the two ends of the ellipse, where the sides already meet, have none.
  for (const bool detail : {false, true})
  {
    const Eigen::Matrix3Xd before = s.positions({0.0, detail}), after = s.positions({1.0, detail});
    int unpaired = 0;
    double gap = 0.0, widest = 0.0;
    for (Eigen::Index v : onBorder)
    {
      double nearest = std::numeric_limits<double>::infinity(), apart = 0.0;
      for (Eigen::Index w : onBorder)
        if (w != v && (before.col(w) - before.col(v)).norm() > 0.05)
        {
          const double dist = (after.col(w) - after.col(v)).norm();
          if (dist < nearest)
          {
            nearest = dist;
            apart = (before.col(w) - before.col(v)).norm();
          }
        }
      if (nearest > 0.01)
      {
        ++unpaired;
        continue;
      }
      gap = std::max(gap, nearest);
      widest = std::max(widest, apart);
    }
    std::printf("[closure, %s range detail] %zu border vertices (resolution %d): up to %.3g mm apart before, "
                "largest gap after %.3g mm; %d without a partner\n",
                detail ? "with" : "without", onBorder.size(), s.resolution(), widest, gap, unpaired);
    EXPECT_EQ(unpaired, 2);
    EXPECT_GT(widest, 1.0);
    if (detail)
      EXPECT_LT(gap, 2.0 * d.largestRangeDetail + 1e-9); // the two sides' offsets to the scan differ a little
    else
      EXPECT_LT(gap, 1e-9);
  }
}

TEST(PlanDisplay, ASymmetricEllipseGivesAMirrorSymmetricStressField)
{
  const PlanDisplay d = buildPlanDisplay(ellipse(), phantom().skin);
  const fem::DisplaySurface& s = d.surface;
  const Eigen::Matrix3Xd& x = s.undeformedPositions();
  std::map<std::tuple<long, long, long>, Eigen::Index> index;
  auto key = [](const Eigen::Vector3d& y) {
    return std::make_tuple(std::lround(y.x() * 1e5), std::lround(y.y() * 1e5), std::lround(y.z() * 1e5));
  };
  for (Eigen::Index v = 0; v < x.cols(); ++v)
    index[key(x.col(v))] = v;
  const Eigen::VectorXd vonMises = s.vonMises(), mean = s.meanStress(), strain = s.equivalentStrain();
  const Eigen::Matrix3Xd after = d.positions(1.0);
  const double scaleVm = vonMises.maxCoeff(), scaleMean = mean.cwiseAbs().maxCoeff(), scaleStrain = strain.maxCoeff();
  for (int mirror = 0; mirror < 2; ++mirror)
  {
    const Eigen::Vector3d flip = mirror == 0 ? Eigen::Vector3d(1, -1, 1) : Eigen::Vector3d(1, 1, -1);
    int matched = 0;
    double worstStress = 0.0, worstShape = 0.0;
    for (Eigen::Index v = 0; v < x.cols(); ++v)
    {
      const auto it = index.find(key(x.col(v).cwiseProduct(flip)));
      if (it == index.end())
        continue;
      ++matched;
      const Eigen::Index w = it->second;
      worstStress = std::max({worstStress, std::abs(vonMises[v] - vonMises[w]) / scaleVm,
                              std::abs(mean[v] - mean[w]) / scaleMean, std::abs(strain[v] - strain[w]) / scaleStrain});
      worstShape = std::max(worstShape, (after.col(v).cwiseProduct(flip) - after.col(w)).norm());
    }
    std::printf("[mirror %s] %d of %ld vertices have a mirror vertex; largest relative asymmetry of von Mises, "
                "mean stress and strain %.3g; of the deformed surface %.3g mm (von Mises up to %.3g kPa, mean stress "
                "up to %.3g kPa)\n",
                mirror == 0 ? "θ → −θ" : "z → −z", matched, long(x.cols()), worstStress, worstShape, 1e3 * scaleVm,
                1e3 * scaleMean);
    EXPECT_EQ(matched, int(x.cols()));
    EXPECT_LT(worstStress, 1e-6);
    EXPECT_LT(worstShape, 1e-6);
  }
  // Closing the wound stretches the skin: stress where the display is, not zero.
  EXPECT_GT(scaleVm, 0.0);
}

TEST(PlanDisplay, PolyDataCarriesEveryArrayAndIsWrittenAsVtp)
{
  const PlanPrediction& p = ellipse();
  // A colour map that changes with θ and z, to see that each vertex reads its own (θ, z).
  seg::ColourMap colour(phantom().skin.frame());
  for (int j = 0; j < colour.nZ(); ++j)
    for (int i = 0; i < colour.nTheta(); ++i)
      colour.at(i, j) = {std::uint8_t(i % 256), std::uint8_t(j % 256), 200};
  const PlanDisplay d = buildPlanDisplay(p, phantom().skin, &colour);
  const fem::DisplaySurface& s = d.surface;
  for (Eigen::Index v = 0; v < s.vertexCount(); ++v)
  {
    const seg::CylindricalPoint c = phantom().skin.frame().toCylindrical(s.undeformedPositions().col(v));
    ASSERT_EQ(d.skinShade[std::size_t(v)], seg::sampleColour(colour, c.theta, c.z));
  }

  const std::filesystem::path folder = std::filesystem::path(CAPS_TEST_ARTIFACTS_DIR) / "plan-display";
  std::filesystem::create_directories(folder);
  writePlanDisplay(d, folder / "skin-before.vtp", folder / "skin-after.vtp");
  for (const double scale : {0.0, 1.0})
  {
    auto reader = vtkSmartPointer<vtkXMLPolyDataReader>::New();
    reader->SetFileName((folder / (scale == 0.0 ? "skin-before.vtp" : "skin-after.vtp")).string().c_str());
    reader->Update();
    vtkPolyData* read = reader->GetOutput();
    ASSERT_EQ(read->GetNumberOfPoints(), vtkIdType(s.vertexCount()));
    ASSERT_EQ(read->GetNumberOfPolys(), vtkIdType(s.polygons().size()));
    const Eigen::Matrix3Xd x = d.positions(scale);
    double worst = 0.0;
    for (vtkIdType v = 0; v < read->GetNumberOfPoints(); ++v)
      worst = std::max(worst, (Eigen::Vector3d(read->GetPoint(v)) - x.col(v)).norm());
    EXPECT_LT(worst, 1e-12);
    const std::map<std::string, int> expected = {{"displacement_mm", 3},   {"displacement_magnitude_mm", 1},
                                                 {"von_mises_kPa", 1},     {"mean_stress_kPa", 1},
                                                 {"stress_kPa", 6},        {"strain", 6},
                                                 {"equivalent_strain", 1}, {"volumetric_strain", 1},
                                                 {"range_detail_mm", 3},   {"skin_shade", 3},
                                                 {"element", 1},           {"rst", 3}};
    for (const auto& [name, components] : expected)
    {
      vtkDataArray* a = read->GetPointData()->GetArray(name.c_str());
      ASSERT_NE(a, nullptr) << name;
      EXPECT_EQ(a->GetNumberOfComponents(), components) << name;
      EXPECT_EQ(a->GetNumberOfTuples(), read->GetNumberOfPoints()) << name;
      bool finite = true;
      for (vtkIdType t = 0; t < a->GetNumberOfTuples(); ++t)
        for (int c = 0; c < components; ++c)
          finite = finite && std::isfinite(a->GetComponent(t, c));
      EXPECT_TRUE(finite) << name;
    }
    EXPECT_EQ(read->GetPointData()->GetArray("skin_shade")->GetDataType(), VTK_UNSIGNED_CHAR);
    EXPECT_EQ(read->GetPointData()->GetArray("element")->GetDataType(), VTK_INT);
    // The arrays are the surface's, in its units.
    vtkDataArray* vm = read->GetPointData()->GetArray("von_mises_kPa");
    const Eigen::VectorXd vonMises = s.vonMises();
    for (vtkIdType v = 0; v < read->GetNumberOfPoints(); v += 97)
      EXPECT_NEAR(vm->GetComponent(v, 0), 1e3 * vonMises[v], 1e-9 * (1.0 + 1e3 * vonMises[v]));
    EXPECT_EQ(read->GetFieldData()->GetArray("displacement_scale")->GetComponent(0, 0), scale);
  }
}

/// A CT of the phantom: tissue out to r = 81.5 mm (the skin map says 80; the
/// extra keeps the trilinear reads away from the air), +50 HU (dermis) on the
/// x > 0 side of the head and −120 HU (fat) on the other, air beyond;
/// 1 mm voxels over |z| ≤ 30 mm (the plans' regions lie within).
vtkSmartPointer<vtkImageData> phantomCt()
{
  auto ct = vtkSmartPointer<vtkImageData>::New();
  ct->SetDimensions(181, 181, 61);
  ct->SetOrigin(-90, -90, -30);
  ct->SetSpacing(1, 1, 1);
  ct->AllocateScalars(VTK_SHORT, 1);
  auto* s = static_cast<short*>(ct->GetScalarPointer());
  for (int k = 0; k < 61; ++k)
    for (int j = 0; j < 181; ++j)
      for (int i = 0; i < 181; ++i)
      {
        const double x = i - 90.0, y = j - 90.0;
        *s++ = short(std::hypot(x, y) > 81.5 ? -1000 : x > 0 ? 50 : -120);
      }
  return ct;
}

TEST(PlanDisplay, CtShadeIsTheTissueUnderTheSkin)
{
  const seg::SkinShadeOptions o;
  auto expected = [&](double hu) {
    const double t = (hu - o.darkHu) / (o.lightHu - o.darkHu);
    return Eigen::Vector3d((1 - t) * o.dark[0] + t * o.light[0], (1 - t) * o.dark[1] + t * o.light[1],
                           (1 - t) * o.dark[2] + t * o.light[2]);
  };
  const seg::ColourMap shade = seg::skinShadeFromCt(phantomCt(), phantom().skin, o);
  auto near = [](const seg::Rgb8& c, const Eigen::Vector3d& e) {
    return std::abs(c[0] - e[0]) <= 0.5 && std::abs(c[1] - e[1]) <= 0.5 && std::abs(c[2] - e[2]) <= 0.5;
  };
  // Dermis side (θ = 0, patient left) light, fat side (θ = π) dark, beyond the CT's z grey.
  EXPECT_TRUE(near(seg::sampleColour(shade, 0.0, 0.0), expected(50)));
  EXPECT_TRUE(near(seg::sampleColour(shade, 0.3, 5.0), expected(50)));
  EXPECT_TRUE(near(seg::sampleColour(shade, test::pi - 0.3, -5.0), expected(-120)));
  EXPECT_EQ(seg::sampleColour(shade, 0.0, 50.0), seg::kNoSourceColour);
  EXPECT_EQ(seg::sampleColour(seg::ColourMap(), 0.0, 0.0), seg::kNoSourceColour);
  EXPECT_THROW(seg::skinShadeFromCt(nullptr, phantom().skin), std::invalid_argument);

  // The ellipse lies on the dermis side: every vertex light.
  const PlanDisplay d = buildPlanDisplay(ellipse(), phantom().skin, &shade);
  int light = 0;
  for (const seg::Rgb8& c : d.skinShade)
    light += near(c, expected(50));
  EXPECT_EQ(light, int(d.skinShade.size()));
}

TEST(PlanDisplay, NewSolutionAndNewScaleAreFast)
{
  // A Z-plasty at the command line's defaults (element size 2 mm, region
  // radius 25 mm) on the phantom; the display at the default resolution.
  const ProcedureTemplate* t = test::shippedProcedures().find("z-plasty");
  const IncisionPlan plan = t->place(phantom().skin, {-test::pi / 2, 0.0});
  SimulationOptions o;
  o.threads = 1;
  const PlanPrediction p = simulatePlan(phantom().skin, phantom().bone, plan, o);
  using clock = std::chrono::steady_clock;
  auto ms = [](clock::time_point t0) { return 1e3 * std::chrono::duration<double>(clock::now() - t0).count(); };
  auto t0 = clock::now();
  PlanDisplay d = buildPlanDisplay(p, phantom().skin);
  const double build = ms(t0);
  t0 = clock::now();
  d.surface.setSolution(p.displacements, p.materials);
  const double solution = ms(t0);
  Eigen::Matrix3Xd x(3, d.surface.vertexCount());
  const int frames = 50;
  t0 = clock::now();
  for (int f = 0; f < frames; ++f)
    d.surface.positions({double(f) / (frames - 1), true}, x);
  const double frame = ms(t0) / frames;
  t0 = clock::now();
  const auto poly = planDisplayPolyData(d, 1.0);
  const double polydata = ms(t0);
  std::printf("[display timing] Z-plasty: %ld DOF, %zu skin faces, %ld vertices at resolution %d: build %.1f ms, "
              "new solution %.2f ms, new scale %.3f ms per frame, polydata %.1f ms\n",
              long(p.dofCount), d.surface.faces().size(), long(d.surface.vertexCount()), d.surface.resolution(), build,
              solution, frame, polydata);
  EXPECT_EQ(poly->GetNumberOfPoints(), vtkIdType(d.surface.vertexCount()));
  EXPECT_LT((x - d.positions(1.0)).cwiseAbs().maxCoeff(), 1e-12);
}

} // namespace
} // namespace caps::planning
