#pragma once
/// @file ModalProgress.h
/// @brief A window-modal progress dialog with Cancel, for work that has to
/// stay on the GUI thread (renders that share the display with the views:
/// the plan report, an animation export). The dialog names each step, keeps
/// the scene from being changed underneath, and its TaskProgress returns
/// false once Cancel is pressed (the work then throws seg::Cancelled between
/// steps). Header-only: the panels that use it link Qt5::Widgets themselves.

#include <algorithm>
#include <cmath>
#include <string>

#include <QApplication>
#include <QProgressDialog>
#include <QString>

#include "modules/core/Module.h"

namespace caps {

class ModalProgress
{
public:
  /// @a objectName lets tests find the dialog; @a title may be empty.
  ModalProgress(QWidget* parent, const QString& label, const QString& title, const QString& objectName)
    : dialog_(label, QObject::tr("Cancel"), 0, kSteps, parent)
  {
    dialog_.setObjectName(objectName);
    if (!title.isEmpty())
      dialog_.setWindowTitle(title);
    dialog_.setWindowModality(Qt::WindowModal);
    dialog_.setMinimumDuration(0);
    dialog_.setValue(0);
    QApplication::processEvents();
  }

  /// Shows @a step and the fraction done, lets the dialog repaint and take a
  /// click on Cancel; false once it was pressed. Valid while this object lives.
  TaskProgress progress()
  {
    return [this](double fraction, const std::string& step) {
      dialog_.setLabelText(QString::fromStdString(step));
      dialog_.setValue(int(std::lround(kSteps * std::clamp(fraction, 0.0, 1.0))));
      QApplication::processEvents();
      return !dialog_.wasCanceled();
    };
  }

  /// Fills the bar: the work is done.
  void finish() { dialog_.setValue(kSteps); }

private:
  static constexpr int kSteps = 1000;
  QProgressDialog dialog_;
};

} // namespace caps
