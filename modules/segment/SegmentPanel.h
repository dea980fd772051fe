#pragma once
/// @file SegmentPanel.h
/// @brief The Segment module's minimal panel: the two thresholds and Run.

#include <QWidget>

class QDoubleSpinBox;
class QCheckBox;
class QLabel;
class QTableWidget;
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

protected:
  void showEvent(QShowEvent* event) override;
  void hideEvent(QHideEvent* event) override;

private:
  void run();
  void updateFromScene();
  void updatePreview();
  void updateSurfaces();

  SegmentLogic& logic_;
  ModuleHost& host_;
  int observer_ = -1;
  QDoubleSpinBox* skin_ = nullptr;
  QDoubleSpinBox* bone_ = nullptr;
  QPushButton* run_ = nullptr;
  QLabel* status_ = nullptr;
  QCheckBox* preview_ = nullptr;
  QTableWidget* surfaces_ = nullptr;
  bool surfaces_pending_ = false;
};

} // namespace caps
