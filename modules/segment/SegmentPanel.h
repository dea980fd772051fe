#pragma once
/// @file SegmentPanel.h
/// @brief The Segment module's minimal panel: the two thresholds and Run.

#include <QWidget>

class QDoubleSpinBox;
class QLabel;
class QPushButton;

namespace caps {

class ModuleHost;
class SegmentLogic;

class SegmentPanel : public QWidget
{
  Q_OBJECT
public:
  SegmentPanel(SegmentLogic& logic, ModuleHost& host, QWidget* parent = nullptr);
  ~SegmentPanel() override;

private:
  void run();
  void updateFromScene();

  SegmentLogic& logic_;
  ModuleHost& host_;
  int observer_ = -1;
  QDoubleSpinBox* skin_ = nullptr;
  QDoubleSpinBox* bone_ = nullptr;
  QPushButton* run_ = nullptr;
  QLabel* status_ = nullptr;
};

} // namespace caps
