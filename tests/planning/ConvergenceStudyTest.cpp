// The convergence and sensitivity study (planning::studyConvergence) on the
// cylinder phantom (skin r = 80 mm over bone r = 70 mm): its changes are the
// rows' own differences, the tension settles as the mesh is refined, and the
// rim's condition matters less the farther the rim is from the wound.

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include <gtest/gtest.h>

#include "AnalyticSkins.h"
#include "planning/ConvergenceStudy.h"
#include "segmentation/Progress.h"

namespace caps::planning {
namespace {

TEST(ConvergenceStudy, TheEllipsesTensionSettlesAndTheRimMattersLessFartherOut)
{
  const auto& phantom = test::cylinderPhantom();
  const IncisionPlan plan =
    test::shippedProcedure("elliptical-excision").place(phantom.skin, {0.0, 0.0}, {{"length", 24.0}, {"ratio", 3.0}});
  SimulationOptions options = test::phantomSimulationOptions();
  options.threads = 2;
  ConvergenceLevels levels;
  levels.elementSizes = {3.0, 2.0, 1.4};
  levels.regionRadii = {12.0, 30.0};
  // Progress: each solve announced once ("... (3 of 10)"), its own steps
  // within its share, the fraction never going back.
  int announced = 0, within = 0;
  double last = 0.0;
  bool forward = true;
  const ConvergenceStudy study =
    studyConvergence(phantom.skin, phantom.bone, plan, options, levels, 10.0, [&](double f, const std::string& step) {
      forward = forward && f >= last - 1e-12 && f <= 1.0;
      last = f;
      (step.find(" of 10): ") != std::string::npos ? within : announced) += 1;
      return true;
    });
  ASSERT_EQ(study.rows.size(), 3u + 3u + 4u);
  EXPECT_EQ(announced, 10);
  EXPECT_GT(within, 10);
  EXPECT_TRUE(forward);
  const char* series[] = {"element size",
                          "element size",
                          "element size",
                          "tissue layers",
                          "tissue layers",
                          "tissue layers",
                          "region radius, free rim",
                          "region radius, free rim",
                          "region radius, clamped rim",
                          "region radius, clamped rim"};
  for (std::size_t k = 0; k < study.rows.size(); ++k)
  {
    const ConvergenceRow& r = study.rows[k];
    EXPECT_EQ(r.series, series[k]);
    EXPECT_TRUE(r.computed && r.solved) << r.series << " " << r.value << ": " << r.problem;
    EXPECT_GT(r.tensionPerCentimetre, 0.0);
    EXPECT_GT(r.meanWoundStressKPa, 0.0);
    EXPECT_TRUE(std::isnan(r.gainPercent)); // not a Z-plasty
    std::printf("[ convergence ] %s %.1f: %.4f N/cm, mean %.2f kPa, peak %.2f kPa, moved %.3f mm, %.3f N\n",
                r.series.c_str(), r.value, r.tensionPerCentimetre, r.meanWoundStressKPa, r.peakWoundStressKPa,
                r.largestDisplacement, r.closureForce);
    const bool first = k == 0 || study.rows[k - 1].series != r.series;
    if (first)
      EXPECT_TRUE(std::isnan(r.tensionChange));
    else
    {
      const ConvergenceRow& b = study.rows[k - 1];
      EXPECT_NEAR(r.tensionChange, 100.0 * (r.tensionPerCentimetre - b.tensionPerCentimetre) / r.tensionPerCentimetre,
                  1e-9);
      EXPECT_NEAR(r.displacementChange, 100.0 * (r.largestDisplacement - b.largestDisplacement) / r.largestDisplacement,
                  1e-9);
    }
  }
  EXPECT_EQ(study.rows[1].value, 2.0);
  EXPECT_EQ(study.rows[4].value, 3.0);
  // Refined from 2 to 1.4 mm the tension changes less than from 3 to 2 mm, and by little.
  EXPECT_LT(std::abs(study.rows[2].tensionChange), 8.0);
  EXPECT_LT(std::abs(study.rows[2].tensionChange), std::abs(study.rows[1].tensionChange) + 0.1);
  // A clamped rim holds the skin the wound pulls on; the farther out it is,
  // the less it changes the answer.
  const auto rimEffect = [&](std::size_t freeRow, std::size_t clampedRow) {
    return std::abs(study.rows[clampedRow].tensionPerCentimetre - study.rows[freeRow].tensionPerCentimetre);
  };
  EXPECT_LT(rimEffect(7, 9), rimEffect(6, 8));
  EXPECT_GE(study.rows[8].tensionPerCentimetre, study.rows[6].tensionPerCentimetre);
}

// A cancel stops the study inside a solve, not after it.
TEST(ConvergenceStudy, ACancelStopsTheSolveThatRuns)
{
  const auto& phantom = test::cylinderPhantom();
  const IncisionPlan plan = test::shippedProcedure("elliptical-excision").place(phantom.skin, {0.0, 0.0});
  std::string stoppedAt;
  EXPECT_THROW(studyConvergence(phantom.skin, phantom.bone, plan, test::phantomSimulationOptions(), {}, 10.0,
                                [&](double, const std::string& step) {
                                  if (step.find("): ") == std::string::npos)
                                    return true;
                                  stoppedAt = step;
                                  return false;
                                }),
               seg::Cancelled);
  EXPECT_EQ(stoppedAt.rfind("Convergence study, element size ", 0), 0u) << stoppedAt;
  EXPECT_NE(stoppedAt.find("(1 of "), std::string::npos) << stoppedAt;
}

TEST(ConvergenceStudy, EmptyOrNonPositiveLevelsAreRefused)
{
  const auto& phantom = test::cylinderPhantom();
  const IncisionPlan plan = test::shippedProcedure("elliptical-excision").place(phantom.skin, {0.0, 0.0});
  ConvergenceLevels none;
  none.layerCounts.clear();
  EXPECT_THROW(studyConvergence(phantom.skin, phantom.bone, plan, test::phantomSimulationOptions(), none, 10.0),
               std::invalid_argument);
  ConvergenceLevels negative;
  negative.regionRadii = {-5.0};
  EXPECT_THROW(studyConvergence(phantom.skin, phantom.bone, plan, test::phantomSimulationOptions(), negative, 10.0),
               std::invalid_argument);
}

} // namespace
} // namespace caps::planning
