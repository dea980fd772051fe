#pragma once
/// @file PlanFigures.h
/// @brief The report's figures: the incision on the
/// face from the front, obliquely and in profile; the skin before and after
/// from the same close-up camera; the stress map; the thickness map
/// unwrapped and painted on the face; the storyboard. Renders are made
/// offscreen at print resolution (render/Figure.h).

#include <optional>
#include <string>

#include <QImage>

#include "planning/IncisionPlan.h"
#include "planning/SkinChart.h"
#include "render/Figure.h"

#include "segmentation/RangeMap.h"

namespace caps {
class RangeMapNode;
class Scene;
class VolumeNode;
} // namespace caps

namespace caps::report {

class ReportDocument;
struct PlanFacts;

/// The views of a plan the report and the storyboard show.
enum class PlanView
{
  Front,   ///< the face from the front, the incision drawn
  Oblique, ///< 45° from the side the plan is on
  Profile, ///< 90° from that side
  Before,  ///< close-up of the display surface before the operation, the incision drawn
  After,   ///< the same camera after closure
  Stress,  ///< the closed skin coloured by von Mises stress, with its colour bar
};
/// The patient's whole skin surface (the Segment module's "Skin"), or null.
vtkPolyData* headSkin(const Scene& scene);
/// The polydata of the Surface node named @a name, or null.
vtkPolyData* surfaceNamed(const Scene& scene, const std::string& name);
/// The cut path of @a plan lifted onto the skin every 0.5 mm (§3.3.1: a
/// solid line), its cut points labelled p0, p1, ... when @a labelled (on a
/// long cut the ends and a few between, so labels do not overlap).
render::LineLayer incisionLine(const planning::IncisionPlan& plan, const planning::SkinChart& chart,
                               bool labelled = true);

/// A caption for a view; @a left: the plan is on the patient's left.
std::string planViewName(PlanView view, bool left);

class PlanFigures
{
public:
  /// @a dpi: the figures' resolution at their printed size.
  PlanFigures(Scene& scene, const VolumeNode& volume, double dpi);

  /// The figure of one view of @a plan (only its name and plan are needed,
  /// and its wound stress for Stress), @a printWidthMm wide on paper at this
  /// object's resolution; std::nullopt when the scene lacks the surfaces.
  std::optional<render::Figure> planFigure(const PlanFacts& plan, PlanView view, double printWidthMm,
                                           double heightPerWidth) const;

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
  /// The map of @a role built with the plan's skin map, or null.
  const RangeMapNode* mapOfPlan(const PlanFacts& plan, const std::string& role) const;

  Scene& scene_;
  const VolumeNode& volume_;
  double dpi_;
};

} // namespace caps::report
