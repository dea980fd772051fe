#include "planning/ConvergenceStudy.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>

#include "planning/WoundStress.h"
#include "planning/WoundTension.h"

namespace caps::planning {
namespace {

constexpr double notANumber = std::numeric_limits<double>::quiet_NaN();

void checkLevels(const ConvergenceLevels& levels)
{
  if (levels.elementSizes.empty() || levels.layerCounts.empty() || levels.regionRadii.empty())
    throw std::invalid_argument("a convergence study needs at least one element size, layer count and region radius");
  for (double h : levels.elementSizes)
    if (!(h > 0.0) || !std::isfinite(h))
      throw std::invalid_argument("an element size of the study must be a positive number of mm");
  for (int layers : levels.layerCounts)
    if (layers < 1 || layers > 8)
      throw std::invalid_argument("a layer count of the study must be 1 to 8, not " + std::to_string(layers));
  for (double r : levels.regionRadii)
    if (!(r > 0.0) || !std::isfinite(r))
      throw std::invalid_argument("a region radius of the study must be a positive number of mm");
}

/// The plan solved once with @a options; a failure is the row's problem.
ConvergenceRow solveOnce(const seg::RangeMap& skin, const seg::RangeMap& bone, const IncisionPlan& plan,
                         const SimulationOptions& options, double woundStressRadius)
{
  ConvergenceRow row;
  try
  {
    const PlanPrediction p = simulatePlan(skin, bone, plan, options);
    const WoundStress wound = woundSkinStress(p, woundStressRadius);
    const WoundTension tension = woundTension(p, plan);
    double across = 0.0, length = 0.0;
    for (const WoundLineTension& l : tension.lines)
    {
      across += l.acrossForce;
      length += l.length;
    }
    row.computed = true;
    row.solved = p.check.admissible();
    row.problem = p.check.problem;
    row.closureForce = p.closure.magnitudeSum;
    row.tensionPerCentimetre = length > 0.0 ? 10.0 * across / length : 0.0;
    row.meanWoundStressKPa = 1e3 * wound.meanVonMises;
    row.peakWoundStressKPa = 1e3 * wound.peakVonMises;
    row.gainPercent = p.zPlasty ? 100.0 * p.zPlasty->predicted.fraction : notANumber;
    for (std::size_t v = 0; v < p.skin.original.size(); ++v)
      row.largestDisplacement = std::max(row.largestDisplacement, (p.skin.displaced[v] - p.skin.original[v]).norm());
    row.minDetF = p.check.deformation.minDetF;
  }
  catch (const seg::Cancelled&)
  {
    throw;
  }
  catch (const std::exception& e)
  {
    row.solved = false;
    row.problem = e.what();
  }
  return row;
}

/// A level as the surgeon reads it: "element size 2 mm", "tissue layers 3".
std::string levelText(const std::string& series, double value)
{
  char text[32];
  if (series == "tissue layers")
    std::snprintf(text, sizeof text, "%d", int(std::lround(value)));
  else
    std::snprintf(text, sizeof text, "%.3g mm", value);
  return series + " " + text;
}

double relativeChange(double before, double now)
{
  return std::abs(now) > 0.0 ? 100.0 * (now - before) / std::abs(now) : notANumber;
}

/// Each row's change from the row before it in its series.
void fillChanges(std::vector<ConvergenceRow>& rows)
{
  for (std::size_t k = 0; k < rows.size(); ++k)
  {
    ConvergenceRow& r = rows[k];
    const bool follows = k > 0 && rows[k - 1].series == r.series && rows[k - 1].solved && r.solved;
    const ConvergenceRow* b = follows ? &rows[k - 1] : nullptr;
    r.forceChange = b ? relativeChange(b->closureForce, r.closureForce) : notANumber;
    r.tensionChange = b ? relativeChange(b->tensionPerCentimetre, r.tensionPerCentimetre) : notANumber;
    r.meanStressChange = b ? relativeChange(b->meanWoundStressKPa, r.meanWoundStressKPa) : notANumber;
    r.gainChange = b ? relativeChange(b->gainPercent, r.gainPercent) : notANumber;
    r.displacementChange = b ? relativeChange(b->largestDisplacement, r.largestDisplacement) : notANumber;
  }
}

} // namespace

ConvergenceStudy studyConvergence(const seg::RangeMap& skin, const seg::RangeMap& bone, const IncisionPlan& plan,
                                  const SimulationOptions& options, ConvergenceLevels levels, double woundStressRadius,
                                  const seg::ProgressCallback& progress)
{
  if (levels.elementSizes.empty())
    levels.elementSizes = {1.5 * options.elementSize, options.elementSize, options.elementSize / 1.5};
  checkLevels(levels);
  // The solves of the study, in the order they are tabled.
  struct Solve
  {
    std::string series;
    double value;
    SimulationOptions options;
  };
  std::vector<Solve> solves;
  SimulationOptions base = options;
  base.progress = {};
  for (double h : levels.elementSizes)
  {
    solves.push_back({"element size", h, base});
    solves.back().options.elementSize = h;
  }
  for (int layers : levels.layerCounts)
  {
    solves.push_back({"tissue layers", double(layers), base});
    SimulationOptions& o = solves.back().options;
    o.layerCount = layers;
    // The plan's own materials are per layer: another count takes the defaults.
    if (o.materials.size() != std::size_t(layers))
      o.materials.clear();
  }
  for (const auto& [rim, series] : {std::pair{fem::RimCondition::Free, "region radius, free rim"},
                                    std::pair{fem::RimCondition::Clamped, "region radius, clamped rim"}})
    for (double radius : levels.regionRadii)
    {
      solves.push_back({series, radius, base});
      solves.back().options.regionRadius = radius;
      solves.back().options.rim = rim;
    }
  ConvergenceStudy study;
  const double count = double(solves.size());
  for (std::size_t k = 0; k < solves.size(); ++k)
  {
    const std::string label = "Convergence study, " + levelText(solves[k].series, solves[k].value) + " (" +
                              std::to_string(k + 1) + " of " + std::to_string(solves.size()) + ")";
    seg::reportProgress(progress, double(k) / count, label);
    // Each solve reports within its share, so a cancel stops it mid-solve
    // rather than after a large-deformation solve that may take minutes.
    if (progress)
      solves[k].options.progress = [&progress, label, k, count](double fraction, const std::string& step) {
        return progress((double(k) + std::clamp(fraction, 0.0, 1.0)) / count, label + ": " + step);
      };
    ConvergenceRow row = solveOnce(skin, bone, plan, solves[k].options, woundStressRadius);
    row.series = solves[k].series;
    row.value = solves[k].value;
    study.rows.push_back(std::move(row));
  }
  fillChanges(study.rows);
  return study;
}

} // namespace caps::planning
