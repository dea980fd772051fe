#include "modules/volumes/VolumesLogic.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include <vtkExtractVOI.h>
#include <vtkImageFlip.h>
#include <vtkImageMapToWindowLevelColors.h>
#include <vtkImagePermute.h>
#include <vtkImageResample.h>
#include <vtkMatrix3x3.h>
#include <vtkPNGWriter.h>

#include "scene/Scene.h"
#include "scene/VolumeNode.h"

namespace fs = std::filesystem;

namespace caps {
namespace {

std::string field(const VolumeNode& volume, const std::string& key)
{
  auto it = volume.metadata().find(key);
  return it == volume.metadata().end() || it->second.empty() ? "-" : it->second;
}

// DICOM dates are YYYYMMDD; print them as ISO dates.
std::string isoDate(const std::string& d)
{
  if (d.size() == 8 && std::all_of(d.begin(), d.end(), ::isdigit))
    return d.substr(0, 4) + "-" + d.substr(4, 2) + "-" + d.substr(6, 2);
  return d;
}

// The patient axis (L/P/S with sign) a direction column points along most.
std::string axisLabel(const double column[3])
{
  static const char* positive[3] = {"L", "P", "S"};
  static const char* negative[3] = {"R", "A", "I"};
  int best = 0;
  for (int a = 1; a < 3; ++a)
    if (std::abs(column[a]) > std::abs(column[best]))
      best = a;
  return column[best] >= 0 ? positive[best] : negative[best];
}

} // namespace

seg::CtVolume VolumesLogic::read(const fs::path& path, const seg::CtReadOptions& options)
{
  return seg::readCtVolume(path, options);
}

VolumeNode* VolumesLogic::addVolume(seg::CtVolume volume)
{
  auto node = std::make_unique<VolumeNode>();
  std::string name;
  if (auto it = volume.metadata.find("SeriesDescription"); it != volume.metadata.end())
    name = it->second;
  if (name.empty())
    name = fs::path(volume.sourcePath).filename().string();
  node->setName(name.empty() ? "CT" : name);
  node->setImage(volume.image);
  node->setMetadata(std::move(volume.metadata));
  node->setSourcePath(volume.sourcePath);
  node->setWindowLevel(400.0, 40.0);
  return static_cast<VolumeNode*>(scene().addNode(std::move(node)));
}

VolumeNode* VolumesLogic::findBySource(const fs::path& path) const
{
  std::error_code ec;
  const fs::path wanted = fs::weakly_canonical(path, ec);
  for (Node* node : scene().nodesOfType(NodeType::Volume))
  {
    auto* volume = static_cast<VolumeNode*>(node);
    if (fs::weakly_canonical(volume->sourcePath(), ec) == wanted)
      return volume;
  }
  return nullptr;
}

VolumeNode* VolumesLogic::load(const fs::path& path, const seg::CtReadOptions& options,
                               std::vector<std::string>& warnings)
{
  if (options.seriesUid.empty() && options.seriesIndex < 0)
    if (VolumeNode* existing = findBySource(path))
      return existing;
  seg::CtVolume volume = read(path, options);
  warnings.insert(warnings.end(), volume.warnings.begin(), volume.warnings.end());
  return addVolume(std::move(volume));
}

std::string VolumesLogic::describe(const VolumeNode& volume)
{
  vtkImageData* image = volume.image();
  std::ostringstream out;
  out << std::setprecision(6);
  out << "Source:       " << volume.sourcePath() << "\n";
  if (!image)
    return out.str() + "No image data.\n";
  const int* dims = image->GetDimensions();
  const double* spacing = image->GetSpacing();
  const double* origin = image->GetOrigin();
  vtkMatrix3x3* d = image->GetDirectionMatrix();
  double range[2];
  image->GetScalarRange(range);

  out << "Dimensions:   " << dims[0] << " x " << dims[1] << " x " << dims[2] << " voxels\n";
  out << "Spacing:      " << spacing[0] << " x " << spacing[1] << " x " << spacing[2] << " mm\n";
  out << "Origin:       (" << origin[0] << ", " << origin[1] << ", " << origin[2] << ") mm, patient LPS\n";
  std::string code;
  out << "Orientation:  ";
  for (int c = 0; c < 3; ++c)
  {
    const double column[3] = {d->GetElement(0, c), d->GetElement(1, c), d->GetElement(2, c)};
    out << (c ? "  " : "") << "[" << column[0] << " " << column[1] << " " << column[2] << "]";
    code += axisLabel(column);
  }
  out << " (axes point to " << code << ")\n";
  out << "Extent:       " << spacing[0] * (dims[0] - 1) << " x " << spacing[1] * (dims[1] - 1) << " x "
      << spacing[2] * (dims[2] - 1) << " mm\n";
  out << "Voxel type:   " << image->GetScalarTypeAsString() << "\n";
  out << "HU range:     " << range[0] << " .. " << range[1] << "\n";
  if (!volume.metadata().empty())
  {
    out << "Patient:      " << field(volume, "PatientName") << ", ID " << field(volume, "PatientID") << ", sex "
        << field(volume, "PatientSex") << ", born " << isoDate(field(volume, "PatientBirthDate")) << ", age "
        << field(volume, "PatientAge") << "\n";
    out << "Study:        " << isoDate(field(volume, "StudyDate")) << " '" << field(volume, "StudyDescription")
        << "', UID " << field(volume, "StudyInstanceUID") << "\n";
    out << "Series:       " << field(volume, "Modality") << " '" << field(volume, "SeriesDescription") << "', number "
        << field(volume, "SeriesNumber") << ", UID " << field(volume, "SeriesInstanceUID") << "\n";
    out << "Scanner:      " << field(volume, "Manufacturer") << " " << field(volume, "ManufacturerModelName") << ", "
        << field(volume, "KVP") << " kV, kernel " << field(volume, "ConvolutionKernel") << ", slice thickness "
        << field(volume, "SliceThickness") << " mm, position " << field(volume, "PatientPosition") << "\n";
  }
  return out.str();
}

std::vector<fs::path> VolumesLogic::writeMiddleSlices(const VolumeNode& volume, const fs::path& folder, double window,
                                                      double level)
{
  vtkImageData* image = volume.image();
  if (!image)
    throw std::runtime_error("The volume '" + volume.name() + "' has no image data to export.");
  fs::create_directories(folder);
  const int* dims = image->GetDimensions();
  const double* spacing = image->GetSpacing();
  const double pixel = std::min({spacing[0], spacing[1], spacing[2]});

  struct View
  {
    const char* name;
    int axis;      // the slice axis
    int columns;   // image axis along the picture's columns (left to right)
    int rows;      // image axis along the picture's rows (bottom to top)
    bool flipRows; // axial: anterior (low j) at the top of the picture
  };
  // Radiological orientation: patient left on the right, superior up, face left.
  const View views[3] = {{"axial", 2, 0, 1, true}, {"coronal", 1, 0, 2, false}, {"sagittal", 0, 1, 2, false}};
  std::vector<fs::path> files;
  for (const View& view : views)
  {
    int voi[6] = {0, dims[0] - 1, 0, dims[1] - 1, 0, dims[2] - 1};
    voi[2 * view.axis] = voi[2 * view.axis + 1] = (dims[view.axis] - 1) / 2;
    auto extract = vtkSmartPointer<vtkExtractVOI>::New();
    extract->SetInputData(image);
    extract->SetVOI(voi);
    // Square pixels: resample the in-plane axes to the finest spacing.
    auto resample = vtkSmartPointer<vtkImageResample>::New();
    resample->SetInputConnection(extract->GetOutputPort());
    resample->SetDimensionality(3);
    for (int a = 0; a < 3; ++a)
      resample->SetAxisOutputSpacing(a, a == view.axis ? spacing[a] : pixel);
    resample->SetInterpolationModeToLinear();
    // PNG writers take x as columns and y as rows: bring the slice plane there.
    auto permute = vtkSmartPointer<vtkImagePermute>::New();
    permute->SetInputConnection(resample->GetOutputPort());
    permute->SetFilteredAxes(view.columns, view.rows, view.axis);
    auto colours = vtkSmartPointer<vtkImageMapToWindowLevelColors>::New();
    colours->SetInputConnection(permute->GetOutputPort());
    colours->SetWindow(window);
    colours->SetLevel(level);
    colours->SetOutputFormatToLuminance();
    vtkAlgorithm* last = colours;
    auto flip = vtkSmartPointer<vtkImageFlip>::New();
    if (view.flipRows)
    {
      flip->SetInputConnection(colours->GetOutputPort());
      flip->SetFilteredAxis(1);
      last = flip;
    }
    const fs::path file = folder / (std::string(view.name) + ".png");
    auto writer = vtkSmartPointer<vtkPNGWriter>::New();
    writer->SetInputConnection(last->GetOutputPort());
    writer->SetFileName(file.string().c_str());
    writer->Write();
    if (writer->GetErrorCode() != 0)
      throw std::runtime_error("Could not write " + file.string() + ": is the folder writable?");
    files.push_back(file);
  }
  return files;
}

} // namespace caps
