#pragma once
/// @file PlanComparison.h
/// @brief Two predicted plans side by side (e.g. a Z-plasty
/// at 45° against one at 60°): one 3D view each, one camera for both, the
/// same quantity over the same colour range, so a colour means the same
/// value on the left and on the right.

#include <array>

#include <QWidget>
#include <vtkSmartPointer.h>

#include "modules/results/ResultsLogic.h"

class QLabel;
class vtkCallbackCommand;

namespace caps {

namespace ui {
class ThreeDView;
}

class PlanComparison : public QWidget
{
  Q_OBJECT
public:
  explicit PlanComparison(QWidget* parent = nullptr);
  ~PlanComparison() override;

  /// Shows plan @a left and plan @a right after the operation, coloured by
  /// @a quantity over the range both span. @a summaries go under the names.
  /// @throws std::invalid_argument when a plan has no prediction surfaces.
  void show(ResultsLogic& logic, const PredictedPlan& left, const PredictedPlan& right, ResultQuantity quantity,
            const std::array<QString, 2>& summaries);

  ui::ThreeDView& view(int side) const { return *views_[static_cast<size_t>(side)]; }
  /// The colour range both views use.
  const std::array<double, 2>& colourRange() const { return range_; }

private:
  std::array<ui::ThreeDView*, 2> views_{};
  std::array<QLabel*, 2> titles_{};
  std::array<double, 2> range_{0.0, 0.0};
  vtkSmartPointer<vtkCallbackCommand> camera_observer_;
  unsigned long observer_tag_ = 0;
};

} // namespace caps
