#include "modules/volumes/VolumesPanel.h"

#include <QComboBox>
#include <QFileDialog>
#include <QFontDatabase>
#include <QHBoxLayout>
#include <QHeaderView>
#include <QLabel>
#include <QPlainTextEdit>
#include <QPushButton>
#include <QTreeWidget>
#include <QVBoxLayout>

#include "modules/volumes/VolumesLogic.h"
#include "scene/Scene.h"
#include "scene/VolumeNode.h"

namespace fs = std::filesystem;

namespace caps {

void loadVolumeInBackground(VolumesLogic& logic, ModuleHost& host, const fs::path& path, seg::CtReadOptions options)
{
  const std::string title = "Loading " + path.filename().string();
  host.runTask(title, [&logic, &host, path, options](const TaskProgress& progress) mutable {
    // A folder of several series gives its largest CT series, with a warning.
    options.progress = progress;
    auto volume = std::make_shared<seg::CtVolume>(VolumesLogic::read(path, options));
    return std::function<void()>([&logic, &host, volume]() {
      std::string warnings;
      for (const auto& w : volume->warnings)
        warnings += w + "\n";
      VolumeNode* node = logic.addVolume(std::move(*volume));
      host.showStatus("Loaded '" + node->name() + "'");
      if (!warnings.empty())
        host.showWarning("About this CT", warnings);
    });
  });
}

VolumesPanel::VolumesPanel(VolumesLogic& logic, ModuleHost& host, QWidget* parent)
  : QWidget(parent), logic_(logic), host_(host)
{
  auto* layout = new QVBoxLayout(this);
  auto* buttons = new QHBoxLayout;
  auto* openFolderButton = new QPushButton(tr("Open DICOM folder..."), this);
  auto* openFileButton = new QPushButton(tr("Open image file..."), this);
  openFolderButton->setObjectName("volumes.openFolder");
  openFileButton->setObjectName("volumes.openFile");
  buttons->addWidget(openFolderButton);
  buttons->addWidget(openFileButton);
  layout->addLayout(buttons);

  layout->addWidget(new QLabel(tr("Series in the folder (double-click to load):"), this));
  series_tree_ = new QTreeWidget(this);
  series_tree_->setHeaderLabels(
    {tr("#"), tr("Patient"), tr("Study date"), tr("Description"), tr("Modality"), tr("Slices"), tr("Spacing (mm)")});
  series_tree_->setObjectName("volumes.series");
  series_tree_->setRootIsDecorated(false);
  series_tree_->header()->setSectionResizeMode(QHeaderView::ResizeToContents);
  layout->addWidget(series_tree_, 1);

  layout->addWidget(new QLabel(tr("Loaded volume:"), this));
  volumes_ = new QComboBox(this);
  volumes_->setObjectName("volumes.loaded");
  layout->addWidget(volumes_);
  details_ = new QPlainTextEdit(this);
  details_->setReadOnly(true);
  details_->setFont(QFontDatabase::systemFont(QFontDatabase::FixedFont));
  details_->setLineWrapMode(QPlainTextEdit::NoWrap);
  layout->addWidget(details_, 2);

  connect(openFolderButton, &QPushButton::clicked, this, &VolumesPanel::openFolder);
  connect(openFileButton, &QPushButton::clicked, this, &VolumesPanel::openFile);
  connect(series_tree_, &QTreeWidget::itemDoubleClicked, this, [this](QTreeWidgetItem* item) {
    const int index = item->data(0, Qt::UserRole).toInt();
    if (index < 0 || index >= static_cast<int>(series_.size()))
      return;
    seg::CtReadOptions options;
    options.seriesUid = series_[index].seriesUid;
    loadVolumeInBackground(logic_, host_, folder_, options);
  });
  connect(volumes_, qOverload<int>(&QComboBox::currentIndexChanged), this, &VolumesPanel::showSelectedVolume);

  observer_ = logic_.scene().addObserver([this](SceneEvent event, const Node& node) {
    if (node.type() != NodeType::Volume)
      return;
    if (event == SceneEvent::NodeAboutToBeRemoved)
    {
      const int index = volumes_->findData(QString::fromStdString(node.id()));
      if (index >= 0)
        volumes_->removeItem(index);
    }
    else
      updateFromScene();
  });
  updateFromScene();
}

VolumesPanel::~VolumesPanel()
{
  logic_.scene().removeObserver(observer_);
}

void VolumesPanel::openFolder()
{
  const QString folder = QFileDialog::getExistingDirectory(this, tr("Open a DICOM folder"), QString());
  if (folder.isEmpty())
    return;
  const fs::path path = folder.toStdString();
  host_.runTask("Scanning " + path.filename().string(), [this, path](const TaskProgress&) {
    auto series = std::make_shared<std::vector<seg::DicomSeriesInfo>>(seg::listDicomSeries(path));
    return std::function<void()>([this, path, series]() {
      showSeries(path, *series);
      if (series->empty())
        host_.showError("No DICOM series", "No readable DICOM slices in " + path.string() +
                                             ". Choose the folder that holds the CT slices.");
      else if (series->size() == 1)
        loadVolumeInBackground(logic_, host_, path);
      else
        host_.showStatus("The folder holds " + std::to_string(series->size()) +
                         " series: double-click the one to load.");
    });
  });
}

void VolumesPanel::openFile()
{
  const QString file =
    QFileDialog::getOpenFileName(this, tr("Open a CT image"), QString(),
                                 tr("CT images (*.nii *.nii.gz *.nrrd *.nhdr *.mha *.mhd *.dcm);;All files (*)"));
  if (!file.isEmpty())
    loadVolumeInBackground(logic_, host_, file.toStdString());
}

void VolumesPanel::showSeries(const fs::path& folder, const std::vector<seg::DicomSeriesInfo>& series)
{
  folder_ = folder;
  series_ = series;
  series_tree_->clear();
  for (size_t i = 0; i < series.size(); ++i)
  {
    const auto& s = series[i];
    auto* item = new QTreeWidgetItem(series_tree_);
    item->setText(0, QString::number(i + 1));
    item->setText(1, QString::fromStdString(s.patientName));
    item->setText(2, QString::fromStdString(s.studyDate));
    item->setText(3, QString::fromStdString(s.seriesDescription));
    item->setText(4, QString::fromStdString(s.modality));
    item->setText(5, QString::number(s.sliceCount));
    item->setText(6, QString("%1 x %2 x %3")
                       .arg(s.pixelSpacing[1], 0, 'g', 4)
                       .arg(s.pixelSpacing[0], 0, 'g', 4)
                       .arg(s.sliceThickness, 0, 'g', 4));
    item->setData(0, Qt::UserRole, static_cast<int>(i));
  }
}

void VolumesPanel::updateFromScene()
{
  const QString current = volumes_->currentData().toString();
  QSignalBlocker block(volumes_);
  volumes_->clear();
  for (Node* node : logic_.scene().nodesOfType(NodeType::Volume))
    volumes_->addItem(QString::fromStdString(node->name()), QString::fromStdString(node->id()));
  int index = volumes_->findData(current);
  if (index < 0)
    index = volumes_->count() - 1; // the newest volume
  volumes_->setCurrentIndex(index);
  showSelectedVolume();
}

void VolumesPanel::showSelectedVolume()
{
  const std::string id = volumes_->currentData().toString().toStdString();
  auto* volume = id.empty() ? nullptr : logic_.scene().nodeAs<VolumeNode>(id);
  details_->setPlainText(volume ? QString::fromStdString(VolumesLogic::describe(*volume))
                                : tr("No volume loaded. Open a DICOM folder or an image file, "
                                     "or drop one on the window."));
}

} // namespace caps
