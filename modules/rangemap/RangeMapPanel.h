#pragma once
/// @file RangeMapPanel.h
/// @brief The RangeMap module's minimal panel: Run, and the thickness statistics.

#include <QWidget>

class QCheckBox;
class QLabel;
class QPushButton;

namespace caps {

class ModuleHost;
class RangeMapLogic;

class RangeMapPanel : public QWidget
{
  Q_OBJECT
public:
  RangeMapPanel(RangeMapLogic& logic, ModuleHost& host, QWidget* parent = nullptr);
  ~RangeMapPanel() override;

private:
  void run();
  void updateFromScene();

  RangeMapLogic& logic_;
  ModuleHost& host_;
  int observer_ = -1;
  QCheckBox* smooth_ = nullptr;
  QPushButton* run_ = nullptr;
  QLabel* status_ = nullptr;
};

} // namespace caps
