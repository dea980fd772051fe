#pragma once
/// @file VolumesPanel.h
/// @brief The Volumes module's panel: open a CT, browse a folder's series,
/// read a volume's metadata.

#include <filesystem>
#include <vector>

#include <QWidget>

#include "segmentation/CtReader.h"

class QComboBox;
class QPlainTextEdit;
class QTreeWidget;

namespace caps {

class ModuleHost;
class VolumesLogic;

/// Loads @a path in the background with progress and cancel, then adds the
/// volume to the scene. A folder with several series loads its largest CT
/// series unless @a options names another.
void loadVolumeInBackground(VolumesLogic& logic, ModuleHost& host, const std::filesystem::path& path,
                            seg::CtReadOptions options = {});

class VolumesPanel : public QWidget
{
  Q_OBJECT
public:
  VolumesPanel(VolumesLogic& logic, ModuleHost& host, QWidget* parent = nullptr);
  ~VolumesPanel() override;

private:
  void openFolder();
  void openFile();
  void showSeries(const std::filesystem::path& folder, const std::vector<seg::DicomSeriesInfo>& series);
  void updateFromScene();
  void showSelectedVolume();

  VolumesLogic& logic_;
  ModuleHost& host_;
  int observer_ = -1;
  std::filesystem::path folder_;
  std::vector<seg::DicomSeriesInfo> series_;
  QTreeWidget* series_tree_ = nullptr;
  QComboBox* volumes_ = nullptr;
  QPlainTextEdit* details_ = nullptr;
};

} // namespace caps
