#pragma once
/// @file PlanFigures.h
/// @brief The report's figures (issue 7 items 1 and 4): the incision on the
/// face from the front, obliquely and in profile; the skin before and after
/// from the same close-up camera; the stress map; the thickness map
/// unwrapped and painted on the face; the storyboard. Renders are made
/// offscreen at print resolution (ReportFigures).

#include <QImage>

#include "segmentation/RangeMap.h"

namespace caps {
class Scene;
class VolumeNode;
} // namespace caps

namespace caps::report {

class ReportDocument;
struct PlanFacts;

class PlanFigures
{
public:
  /// @a dpi: the figures' resolution at their printed size.
  PlanFigures(Scene& scene, const VolumeNode& volume, double dpi);

  /// Front, oblique and profile views of the face with the cut drawn and its
  /// points numbered.
  void addIncisionViews(ReportDocument& doc, const PlanFacts& plan) const;
  /// Before and after from the same camera, and the stress map with its colour bar.
  void addPredictionViews(ReportDocument& doc, const PlanFacts& plan) const;
  /// The thickness map unwrapped (θ, z) and painted on the face, with colour bars in mm.
  void addThicknessViews(ReportDocument& doc, const PlanFacts& plan) const;
  /// The Snapshot nodes in scene order with their captions.
  void addStoryboard(ReportDocument& doc) const;

private:
  /// The skin painted with the thickness under it, from the front.
  void addThicknessOnFace(ReportDocument& doc, const PlanFacts& plan) const;
  /// The skin range map the plan is drawn on.
  seg::RangeMap skinMap(const PlanFacts& plan) const;

  Scene& scene_;
  const VolumeNode& volume_;
  double dpi_;
};

} // namespace caps::report
