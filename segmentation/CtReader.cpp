#include "segmentation/CtReader.h"
#include "segmentation/DicomFileCheck.h"

#include <algorithm>
#include <map>
#include <cmath>
#include <cstring>
#include <set>
#include <sstream>

#include <gdcmScanner.h>
#include <gdcmTrace.h>
#include <itkCommand.h>
#include <itkGDCMImageIO.h>
#include <itkImage.h>
#include <itkImageFileReader.h>
#include <itkImageIOFactory.h>
#include <itkImageSeriesReader.h>
#include <vtkMatrix3x3.h>

namespace fs = std::filesystem;

namespace caps::seg {
namespace {

// DICOM fields kept for the report and the info listing, by keyword.
struct DicomField
{
  const char* tag;
  const char* keyword;
};
constexpr DicomField kKeptFields[] = {
  {"0010|0010", "PatientName"},
  {"0010|0020", "PatientID"},
  {"0010|0030", "PatientBirthDate"},
  {"0010|0040", "PatientSex"},
  {"0010|1010", "PatientAge"},
  {"0008|0020", "StudyDate"},
  {"0008|1030", "StudyDescription"},
  {"0020|000d", "StudyInstanceUID"},
  {"0008|0050", "AccessionNumber"},
  {"0008|103e", "SeriesDescription"},
  {"0020|000e", "SeriesInstanceUID"},
  {"0020|0011", "SeriesNumber"},
  {"0008|0060", "Modality"},
  {"0008|0070", "Manufacturer"},
  {"0008|1090", "ManufacturerModelName"},
  {"0008|0080", "InstitutionName"},
  {"0018|0060", "KVP"},
  {"0018|1210", "ConvolutionKernel"},
  {"0018|0050", "SliceThickness"},
  {"0018|5100", "PatientPosition"},
  {"0018|1120", "GantryDetectorTilt"},
  {"0018|0015", "BodyPartExamined"},
  {"0002|0010", "TransferSyntaxUID"},
};

std::string trim(std::string s)
{
  const auto notSpace = [](unsigned char c) { return !std::isspace(c) && c != '\0'; };
  s.erase(s.begin(), std::find_if(s.begin(), s.end(), notSpace));
  s.erase(std::find_if(s.rbegin(), s.rend(), notSpace).base(), s.end());
  return s;
}

std::string tagValue(itk::GDCMImageIO* io, const char* tag)
{
  std::string value;
  if (!io->GetValueFromTag(tag, value))
    return {};
  return trim(value);
}

// First line of an ITK exception, without the file/line noise.
std::string itkReason(const itk::ExceptionObject& e)
{
  std::string text = e.GetDescription();
  return trim(text.substr(0, text.find('\n')));
}

bool isRegularFile(const fs::path& p)
{
  std::error_code ec;
  return fs::is_regular_file(p, ec);
}

// Reports ITK filter progress to our callback and turns a "stop" answer
// into an abort of the filter.
void watchProgress(itk::ProcessObject* filter, const ProgressCallback& progress, const std::string& step)
{
  if (!progress)
    return;
  filter->AddObserver(itk::ProgressEvent(), [filter, progress, step](const itk::EventObject&) {
    if (!progress(filter->GetProgress(), step))
      filter->AbortGenerateDataOn();
  });
}

template <class PixelT> vtkSmartPointer<vtkImageData> toVtk(itk::Image<PixelT, 3>* image, int vtkType)
{
  const auto region = image->GetLargestPossibleRegion();
  const auto size = region.GetSize();
  auto out = vtkSmartPointer<vtkImageData>::New();
  out->SetDimensions(static_cast<int>(size[0]), static_cast<int>(size[1]), static_cast<int>(size[2]));
  out->SetSpacing(image->GetSpacing()[0], image->GetSpacing()[1], image->GetSpacing()[2]);
  out->SetOrigin(image->GetOrigin()[0], image->GetOrigin()[1], image->GetOrigin()[2]);
  const auto& d = image->GetDirection();
  out->SetDirectionMatrix(d(0, 0), d(0, 1), d(0, 2), d(1, 0), d(1, 1), d(1, 2), d(2, 0), d(2, 1), d(2, 2));
  out->AllocateScalars(vtkType, 1);
  std::memcpy(out->GetScalarPointer(), image->GetBufferPointer(), region.GetNumberOfPixels() * sizeof(PixelT));
  return out;
}

template <class PixelT> constexpr int vtkTypeOf();
template <> constexpr int vtkTypeOf<short>()
{
  return VTK_SHORT;
}
template <> constexpr int vtkTypeOf<float>()
{
  return VTK_FLOAT;
}

template <class PixelT>
CtVolume readSeries(const DicomSeriesInfo& series, const fs::path& folder, const CtReadOptions& options)
{
  using Image = itk::Image<PixelT, 3>;
  auto io = itk::GDCMImageIO::New();
  auto reader = itk::ImageSeriesReader<Image>::New();
  reader->SetImageIO(io);
  reader->SetFileNames(series.files);
  watchProgress(reader, options.progress, "Reading " + std::to_string(series.sliceCount) + " slices");
  try
  {
    reader->Update();
  }
  catch (const itk::ProcessAborted&)
  {
    throw Cancelled();
  }
  catch (const itk::ExceptionObject& e)
  {
    throw CtReadError("Could not read the DICOM series '" + series.seriesDescription + "' in " + folder.string() +
                      ": a slice is damaged or incomplete (" + itkReason(e) +
                      "). Remove or replace the damaged file, or export the series again.");
  }
  CtVolume volume;
  volume.image = toVtk<PixelT>(reader->GetOutput(), vtkTypeOf<PixelT>());
  volume.sourcePath = folder.string();
  for (const auto& field : kKeptFields)
  {
    const std::string value = tagValue(io, field.tag);
    if (!value.empty())
      volume.metadata[field.keyword] = value;
  }
  // ITK stacks the slices with one spacing; check every position and make
  // the grid regular when the stack is not (SliceStack.h).
  if (series.geometry.positions.size() == series.files.size() && series.files.size() > 1)
  {
    const SliceStackReport report = analyseSliceStack(series.geometry);
    if (!report.refusal.empty())
      throw CtReadError("The DICOM series '" + series.seriesDescription + "' in " + folder.string() +
                        " cannot be used: " + report.refusal +
                        ". Export the complete series again from the scanner or PACS.");
    if (report.needsResampling)
    {
      double range[2];
      volume.image->GetScalarRange(range);
      volume.image = resampleSliceStack(volume.image, series.geometry, report, std::min(range[0], -1024.0));
      std::string text = "The slices were resampled to a regular grid of " +
                         std::to_string(volume.image->GetDimensions()[2]) + " slices because ";
      for (size_t i = 0; i < report.problems.size(); ++i)
        text += (i ? "; " : "") + report.problems[i];
      text += ". Values there are interpolated; check the slices concerned.";
      volume.warnings.push_back(text);
    }
    else
    {
      // Regular: keep ITK's voxels, with the spacing of the positions.
      const double* spacing = volume.image->GetSpacing();
      volume.image->SetSpacing(spacing[0], spacing[1], report.spacing);
    }
  }
  return volume;
}

template <class PixelT> CtVolume readFile(const fs::path& path, itk::ImageIOBase* io, const CtReadOptions& options)
{
  using Image = itk::Image<PixelT, 3>;
  auto reader = itk::ImageFileReader<Image>::New();
  reader->SetImageIO(io);
  reader->SetFileName(path.string());
  watchProgress(reader, options.progress, "Reading " + path.filename().string());
  try
  {
    reader->Update();
  }
  catch (const itk::ProcessAborted&)
  {
    throw Cancelled();
  }
  catch (const itk::ExceptionObject& e)
  {
    throw CtReadError("Could not read " + path.string() + ": the file is damaged or incomplete (" + itkReason(e) +
                      ").");
  }
  CtVolume volume;
  volume.image = toVtk<PixelT>(reader->GetOutput(), vtkTypeOf<PixelT>());
  volume.sourcePath = path.string();
  return volume;
}

// "3 files are damaged: a.dcm (the file is cut short ...), b.dcm (...)".
std::string describeDamage(const std::vector<std::pair<std::string, std::string>>& damaged)
{
  std::ostringstream out;
  out << damaged.size() << (damaged.size() == 1 ? " file is" : " files are") << " damaged";
  for (size_t i = 0; i < std::min<size_t>(damaged.size(), 3); ++i)
    out << (i ? "; " : ": ") << damaged[i].first << " (" << damaged[i].second << ")";
  if (damaged.size() > 3)
    out << "; ...";
  return out.str();
}

CtVolume readDicomFolder(const fs::path& folder, const fs::path& requestedFile, const CtReadOptions& options)
{
  const DicomFolderScan scan = scanDicomFolder(folder);
  const auto& series = scan.series;
  if (series.empty())
  {
    std::string message = "No readable DICOM slices in " + folder.string() + ".";
    if (!scan.damaged.empty())
      message += " " + describeDamage(scan.damaged) +
                 ". Export the series again from the "
                 "scanner or PACS.";
    else
      message += " Choose the folder that holds the CT slices, or a NIfTI (.nii), NRRD (.nrrd) "
                 "or MetaImage (.mha) file.";
    throw CtReadError(message);
  }

  const DicomSeriesInfo* chosen = nullptr;
  if (!options.seriesUid.empty())
  {
    for (const auto& s : series)
      if (s.seriesUid == options.seriesUid)
        chosen = &s;
    if (!chosen)
      throw CtReadError("No series with UID " + options.seriesUid + " in " + folder.string() + ".");
  }
  else if (options.seriesIndex >= 0)
  {
    if (options.seriesIndex >= static_cast<int>(series.size()))
      throw CtReadError("Series " + std::to_string(options.seriesIndex + 1) + " asked for, but " + folder.string() +
                        " holds only " + std::to_string(series.size()) + ".");
    chosen = &series[options.seriesIndex];
  }
  else if (!requestedFile.empty())
  {
    const std::string wanted = fs::absolute(requestedFile).lexically_normal().string();
    for (const auto& s : series)
      for (const auto& f : s.files)
        if (fs::absolute(f).lexically_normal().string() == wanted)
          chosen = &s;
    if (!chosen)
      throw CtReadError(requestedFile.string() +
                        " is not a readable DICOM slice: it is damaged, incomplete (truncated) or "
                        "not DICOM. Export the series again, or choose another file.");
  }
  else if (series.size() == 1)
  {
    chosen = &series.front();
  }
  else if (!options.requireSingleSeries)
  {
    // As a PACS viewer would: the CT series with the most slices (the list
    // is sorted largest first), else the largest series.
    for (const auto& s : series)
      if (!chosen && s.modality == "CT")
        chosen = &s;
    if (!chosen)
      chosen = &series.front();
  }
  else
  {
    std::ostringstream m;
    m << folder.string() << " holds " << series.size()
      << " DICOM series; say which one to load (by number or series UID):";
    for (size_t i = 0; i < series.size(); ++i)
      m << "\n  " << describeSeries(series[i], static_cast<int>(i) + 1);
    throw CtReadError(m.str());
  }

  // Whole-HU rescales fit int16 and halve the memory of a float volume.
  auto io = itk::GDCMImageIO::New();
  io->SetFileName(chosen->files.front());
  double slope = 1.0, intercept = 0.0;
  try
  {
    io->ReadImageInformation();
    slope = io->GetRescaleSlope();
    intercept = io->GetRescaleIntercept();
  }
  catch (const itk::ExceptionObject& e)
  {
    throw CtReadError("Could not read the first slice " + chosen->files.front() + " (" + itkReason(e) + ").");
  }
  const bool wholeHu = slope == std::round(slope) && intercept == std::round(intercept) && std::abs(slope) <= 1.0;
  CtVolume volume = wholeHu ? readSeries<short>(*chosen, folder, options) : readSeries<float>(*chosen, folder, options);

  if (!scan.damaged.empty())
    volume.warnings.push_back(describeDamage(scan.damaged) +
                              " and were skipped. If they are slices of this series, the volume "
                              "has gaps: export the series again.");
  if (series.size() > 1 && options.seriesUid.empty() && options.seriesIndex < 0)
  {
    std::string others;
    for (size_t i = 0; i < series.size(); ++i)
      if (&series[i] != chosen)
        others += "\n  " + describeSeries(series[i], static_cast<int>(i) + 1);
    volume.warnings.push_back("The folder holds " + std::to_string(series.size()) + " series; loaded '" +
                              chosen->seriesDescription + "' (" + std::to_string(chosen->sliceCount) +
                              " slices). The others:" + others);
  }
  if (!chosen->modality.empty() && chosen->modality != "CT")
    volume.warnings.push_back("This is a " + chosen->modality +
                              " series, not CT: its values are not Hounsfield units, so the skin "
                              "and bone thresholds will not find skin and bone.");
  return volume;
}

/// The regular files of @a folder, sorted by name.
std::vector<fs::path> filesOf(const fs::path& folder)
{
  std::vector<fs::path> files;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(folder, ec))
    if (entry.is_regular_file(ec))
      files.push_back(entry.path());
  if (ec)
    throw CtReadError("Cannot list " + folder.string() + ": " + ec.message() + ".");
  std::sort(files.begin(), files.end());
  return files;
}

/// The DICOM tags a series is grouped, sorted and described by, read from
/// every sound file with GDCM's scanner.
class SeriesTags
{
public:
  inline static const gdcm::Tag seriesUid{0x0020, 0x000e}, orientation{0x0020, 0x0037}, position{0x0020, 0x0032},
    instance{0x0020, 0x0013}, rows{0x0028, 0x0010}, columns{0x0028, 0x0011}, spacing{0x0028, 0x0030},
    thickness{0x0018, 0x0050}, patientName{0x0010, 0x0010}, patientId{0x0010, 0x0020}, studyDate{0x0008, 0x0020},
    description{0x0008, 0x103e}, modality{0x0008, 0x0060};

  SeriesTags(const gdcm::Directory::FilenamesType& files, const fs::path& folder)
  {
    for (const auto& tag : {seriesUid, orientation, position, instance, rows, columns, spacing, thickness, patientName,
                            patientId, studyDate, description, modality})
      scanner_.AddTag(tag);
    if (!scanner_.Scan(files))
      throw CtReadError("Could not scan " + folder.string() + " for DICOM files.");
  }

  bool parsed(const std::string& file) const { return scanner_.IsKey(file.c_str()); }

  std::string value(const std::string& file, const gdcm::Tag& tag) const
  {
    const char* v = scanner_.GetValue(file.c_str(), tag);
    return v ? trim(v) : std::string();
  }

  /// A multi-valued tag's numbers ("a\b\c").
  std::vector<double> numbers(const std::string& file, const gdcm::Tag& tag) const
  {
    std::vector<double> out;
    std::stringstream in(value(file, tag));
    std::string item;
    while (std::getline(in, item, '\\'))
      out.push_back(std::atof(item.c_str()));
    return out;
  }

private:
  // GetValue and IsKey are not const in GDCM; reading does not change it.
  mutable gdcm::Scanner scanner_;
};

/// Groups like ITK's "series details": same UID, orientation and matrix, in
/// the order first met; files GDCM cannot parse go to @a damaged.
std::vector<std::vector<std::string>> groupBySeries(const gdcm::Directory::FilenamesType& sound, const SeriesTags& tags,
                                                    std::vector<std::pair<std::string, std::string>>& damaged)
{
  std::map<std::string, std::vector<std::string>> groups;
  std::vector<std::string> order;
  for (const auto& file : sound)
  {
    if (!tags.parsed(file))
    {
      damaged.emplace_back(fs::path(file).filename().string(), "GDCM cannot parse it");
      continue;
    }
    const std::string key = tags.value(file, SeriesTags::seriesUid) + "|" + tags.value(file, SeriesTags::orientation) +
                            "|" + tags.value(file, SeriesTags::rows) + "x" + tags.value(file, SeriesTags::columns);
    if (!groups.count(key))
      order.push_back(key);
    groups[key].push_back(file);
  }
  std::vector<std::vector<std::string>> out;
  for (const auto& key : order)
    out.push_back(std::move(groups[key]));
  return out;
}

/// One series: its files sorted along the slice normal (row x column
/// direction; by instance number when positions are missing), its
/// identifying fields and its slice geometry.
DicomSeriesInfo seriesInfoOf(std::vector<std::string> group, const SeriesTags& tags)
{
  using T = SeriesTags;
  const std::string first = group.front();
  const auto iop = tags.numbers(first, T::orientation);
  double normal[3] = {0, 0, 1};
  if (iop.size() == 6)
  {
    normal[0] = iop[1] * iop[5] - iop[2] * iop[4];
    normal[1] = iop[2] * iop[3] - iop[0] * iop[5];
    normal[2] = iop[0] * iop[4] - iop[1] * iop[3];
  }
  const auto along = [&](const std::string& file) {
    const auto ipp = tags.numbers(file, T::position);
    if (ipp.size() != 3)
      return std::atof(tags.value(file, T::instance).c_str());
    return ipp[0] * normal[0] + ipp[1] * normal[1] + ipp[2] * normal[2];
  };
  std::stable_sort(group.begin(), group.end(), [&](const auto& a, const auto& b) { return along(a) < along(b); });

  DicomSeriesInfo info;
  info.files = group;
  info.sliceCount = static_cast<int>(group.size());
  info.seriesUid = tags.value(first, T::seriesUid);
  info.patientName = tags.value(first, T::patientName);
  info.patientId = tags.value(first, T::patientId);
  info.studyDate = tags.value(first, T::studyDate);
  info.seriesDescription = tags.value(first, T::description);
  info.modality = tags.value(first, T::modality);
  const auto pixel = tags.numbers(first, T::spacing);
  if (pixel.size() == 2)
  {
    info.pixelSpacing[0] = pixel[0];
    info.pixelSpacing[1] = pixel[1];
    // DICOM Pixel Spacing is (between rows, between columns).
    info.geometry.pixelSpacing[0] = pixel[1];
    info.geometry.pixelSpacing[1] = pixel[0];
  }
  info.sliceThickness = std::atof(tags.value(first, T::thickness).c_str());
  if (iop.size() == 6)
  {
    info.geometry.row = {iop[0], iop[1], iop[2]};
    info.geometry.column = {iop[3], iop[4], iop[5]};
  }
  for (const auto& file : group)
  {
    const auto ipp = tags.numbers(file, T::position);
    if (ipp.size() != 3)
    {
      info.geometry.positions.clear();
      break;
    }
    info.geometry.positions.push_back({ipp[0], ipp[1], ipp[2]});
  }
  if (info.geometry.positions.size() > 1)
    info.sliceSpacing = analyseSliceStack(info.geometry).spacing;
  return info;
}

} // namespace

DicomFolderScan scanDicomFolder(const fs::path& folder)
{
  // GDCM's console warnings (odd VRs in private tags) mean nothing to a user;
  // what matters is reported through our own messages.
  gdcm::Trace::WarningOff();
  DicomFolderScan scan;
  // Damaged files never reach GDCM (see DicomFileCheck.h).
  gdcm::Directory::FilenamesType sound;
  for (const auto& file : filesOf(folder))
  {
    const DicomFileCheck check = checkDicomFile(file);
    if (check.kind == DicomFileKind::Sound)
      sound.push_back(file.string());
    else if (check.kind == DicomFileKind::Damaged)
      scan.damaged.emplace_back(file.filename().string(), check.problem);
  }
  if (sound.empty())
    return scan;
  const SeriesTags tags(sound, folder);
  for (auto& group : groupBySeries(sound, tags, scan.damaged))
    scan.series.push_back(seriesInfoOf(std::move(group), tags));
  // The largest series first.
  std::stable_sort(scan.series.begin(), scan.series.end(),
                   [](const auto& a, const auto& b) { return a.sliceCount > b.sliceCount; });
  return scan;
}

std::vector<DicomSeriesInfo> listDicomSeries(const fs::path& folder)
{
  return scanDicomFolder(folder).series;
}

std::string describeSeries(const DicomSeriesInfo& s, int index)
{
  std::ostringstream out;
  out << index << ": " << (s.modality.empty() ? "?" : s.modality) << " '" << s.seriesDescription << "' " << s.sliceCount
      << " slice" << (s.sliceCount == 1 ? "" : "s") << ", " << s.pixelSpacing[1] << " x " << s.pixelSpacing[0]
      << " mm pixels, " << s.sliceThickness << " mm thick";
  if (s.sliceSpacing > 0)
    out << " every " << s.sliceSpacing << " mm";
  out << ", patient " << s.patientName << ", study date " << s.studyDate << ", UID " << s.seriesUid;
  return out.str();
}

// readCtVolume without the deidentification step.
static CtVolume readCtVolumeAsStored(const fs::path& path, const CtReadOptions& options)
{
  // Our messages replace ITK's warnings on the console (e.g. uneven slices).
  itk::Object::GlobalWarningDisplayOff();
  std::error_code ec;
  if (!fs::exists(path, ec))
    throw CtReadError("No such file or folder: " + path.string() + ".");
  if (fs::is_directory(path, ec))
    return readDicomFolder(path, {}, options);
  if (!isRegularFile(path))
    throw CtReadError(path.string() + " is not a file or a folder.");
  if (fs::file_size(path, ec) == 0)
    throw CtReadError(path.string() + " is empty (0 bytes). Choose the CT series folder or an "
                                      "image file.");

  // DICOM first: a slice stands for the series it belongs to, as in a PACS
  // viewer. A damaged file must not reach GDCM at all (DicomFileCheck.h).
  const DicomFileCheck check = checkDicomFile(path);
  if (check.kind == DicomFileKind::Damaged)
    throw CtReadError(path.string() + " is a damaged DICOM file: " + check.problem +
                      ". Export it again from the scanner or PACS.");
  if (check.kind == DicomFileKind::Sound)
    return readDicomFolder(path.parent_path().empty() ? fs::path(".") : path.parent_path(), path, options);

  auto io = itk::ImageIOFactory::CreateImageIO(path.string().c_str(), itk::IOFileModeEnum::ReadMode);
  if (!io)
    throw CtReadError(path.string() + " is not an image CAPS can read. Choose a DICOM series folder, or a NIfTI "
                                      "(.nii, .nii.gz), NRRD (.nrrd, .nhdr) or MetaImage (.mha, .mhd) file.");
  try
  {
    io->SetFileName(path.string());
    io->ReadImageInformation();
  }
  catch (const itk::ExceptionObject& e)
  {
    throw CtReadError("Could not read the header of " + path.string() + " (" + itkReason(e) +
                      "). The file is damaged or not an image.");
  }
  if (io->GetNumberOfDimensions() != 3)
    throw CtReadError(path.string() + " has " + std::to_string(io->GetNumberOfDimensions()) +
                      " dimensions; CAPS needs a 3D CT volume.");
  if (io->GetNumberOfComponents() != 1)
    throw CtReadError(path.string() + " has " + std::to_string(io->GetNumberOfComponents()) +
                      " values per voxel (a colour image?); CAPS needs a grey-level CT volume.");
  using C = itk::IOComponentEnum;
  const auto component = io->GetComponentType();
  const bool fitsShort = component == C::CHAR || component == C::UCHAR || component == C::SHORT;
  return fitsShort ? readFile<short>(path, io, options) : readFile<float>(path, io, options);
}

const std::vector<std::string>& identifyingFields()
{
  static const std::vector<std::string> fields = {"PatientName",       "PatientID",       "PatientBirthDate",
                                                  "AccessionNumber",   "InstitutionName", "StudyInstanceUID",
                                                  "SeriesInstanceUID", "StudyDate"};
  return fields;
}

CtVolume readCtVolume(const fs::path& path, const CtReadOptions& options)
{
  CtVolume volume = readCtVolumeAsStored(path, options);
  if (options.deidentify && !volume.metadata.empty())
  {
    for (const auto& field : identifyingFields())
      volume.metadata.erase(field);
    volume.metadata["PatientName"] = "Anonymous";
    volume.metadata["Deidentified"] = "yes";
  }
  return volume;
}

} // namespace caps::seg
