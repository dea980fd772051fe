// How much the damage check and the series scan cost on top of ITK's own
// DICOM series reading, on the embedded sample (295 JPEG 2000 slices).
// Prints times and ratios against plain ITK (GDCMSeriesFileNames +
// ImageSeriesReader) measured in the same run. Not a test.

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>

#include <itkGDCMImageIO.h>
#include <itkGDCMSeriesFileNames.h>
#include <itkImage.h>
#include <itkImageSeriesReader.h>

#include "segmentation/CtReader.h"
#include "segmentation/DicomFileCheck.h"
#include "bench/BestOf.h"

namespace fs = std::filesystem;

using caps::bench::secondsOf;

int main(int argc, char** argv)
{
  const fs::path folder = argc > 1 ? fs::path(argv[1]) : fs::path(CAPS_SAMPLE_CT);
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 3;
  std::printf("CT reading benchmark on %s (best of %d)\n", folder.c_str(), repeats);

  const double plainItk = secondsOf(
    [&] {
      auto names = itk::GDCMSeriesFileNames::New();
      names->SetDirectory(folder.string());
      auto reader = itk::ImageSeriesReader<itk::Image<short, 3>>::New();
      reader->SetImageIO(itk::GDCMImageIO::New());
      reader->SetFileNames(names->GetFileNames(names->GetSeriesUIDs().front()));
      reader->Update();
    },
    repeats);

  const double check = secondsOf(
    [&] {
      for (const auto& entry : fs::directory_iterator(folder))
        caps::seg::checkDicomFile(entry.path());
    },
    repeats);

  const double scan = secondsOf([&] { caps::seg::scanDicomFolder(folder); }, repeats);
  const double caps = secondsOf([&] { caps::seg::readCtVolume(folder); }, repeats);

  std::printf("  plain ITK series read      %8.3f s  (reference)\n", plainItk);
  std::printf("  damage check, all files    %8.3f s  ratio %.3f\n", check, check / plainItk);
  std::printf("  scan (check + group/sort)  %8.3f s  ratio %.3f\n", scan, scan / plainItk);
  std::printf("  caps readCtVolume          %8.3f s  ratio %.3f\n", caps, caps / plainItk);
  return 0;
}
