#include "segmentation/RangeMapImage.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <map>
#include <stdexcept>

#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkPNGReader.h>
#include <vtkPNGWriter.h>
#include <vtkPointData.h>
#include <vtkSmartPointer.h>

namespace caps::seg {

namespace {

constexpr const char* kOffset = "CAPS:range-offset-mm";
constexpr const char* kStep = "CAPS:range-step-mm";
constexpr const char* kOrigin = "CAPS:frame-origin";
constexpr const char* kDirection = "CAPS:frame-direction";
constexpr const char* kZRange = "CAPS:frame-z-range";

std::string number(double x)
{
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.17g", x);
  return buffer;
}

std::string vector3(const Eigen::Vector3d& v)
{
  return number(v.x()) + " " + number(v.y()) + " " + number(v.z());
}

void writePng(vtkImageData* image, const std::string& path, const std::map<std::string, std::string>& text)
{
  auto writer = vtkSmartPointer<vtkPNGWriter>::New();
  writer->SetFileName(path.c_str());
  writer->SetInputData(image);
  for (const auto& [key, value] : text)
    writer->AddText(key.c_str(), value.c_str());
  writer->Write();
  if (writer->GetErrorCode() != 0 || !std::filesystem::is_regular_file(path))
    throw std::runtime_error("could not write the image " + path);
}

struct PngContents
{
  vtkSmartPointer<vtkImageData> image;
  std::map<std::string, std::string> text;
};

PngContents readPng(const std::string& path)
{
  if (!std::filesystem::is_regular_file(path))
    throw std::runtime_error("the image " + path + " does not exist or is not a file");
  auto reader = vtkSmartPointer<vtkPNGReader>::New();
  if (!reader->CanReadFile(path.c_str()))
    throw std::runtime_error("the image " + path + " is not a readable PNG file");
  reader->SetFileName(path.c_str());
  reader->Update();
  PngContents out;
  out.image = reader->GetOutput();
  const auto n = static_cast<int>(reader->GetNumberOfTextChunks());
  for (int k = 0; k < n; ++k)
    if (reader->GetTextKey(k) && reader->GetTextValue(k))
      out.text[reader->GetTextKey(k)] = reader->GetTextValue(k);
  if (!out.image || out.image->GetNumberOfPoints() == 0)
    throw std::runtime_error("the image " + path + " has no pixels");
  return out;
}

void checkSize(vtkImageData* image, const CylindricalFrame& frame, const std::string& path)
{
  int dims[3];
  image->GetDimensions(dims);
  if (dims[0] != frame.nTheta() || dims[1] != frame.nZ() || dims[2] != 1)
    throw std::runtime_error("the image " + path + " is " + std::to_string(dims[0]) + " x " + std::to_string(dims[1]) +
                             " pixels, but the map needs " + std::to_string(frame.nTheta()) + " x " +
                             std::to_string(frame.nZ()) + " (was it resized in the image editor?)");
}

double parseNumber(const std::map<std::string, std::string>& text, const char* key, const std::string& path)
{
  const auto it = text.find(key);
  if (it == text.end())
    throw std::runtime_error(std::string("the range map image ") + path + " has lost its '" + key +
                             "' text chunk (the image editor may have dropped it): read it with a known frame "
                             "and encoding");
  return std::stod(it->second);
}

Eigen::Vector3d parseVector(const std::map<std::string, std::string>& text, const char* key, const std::string& path)
{
  const auto it = text.find(key);
  if (it == text.end())
    throw std::runtime_error(std::string("the range map image ") + path + " has lost its '" + key +
                             "' text chunk: read it with a known frame and encoding");
  Eigen::Vector3d v;
  if (std::sscanf(it->second.c_str(), "%lf %lf %lf", &v.x(), &v.y(), &v.z()) != 3)
    throw std::runtime_error(std::string("the '") + key + "' text chunk of " + path + " is not three numbers");
  return v;
}

} // namespace

RangeMapImageEncoding rangeMapImageEncoding(const RangeMap& map)
{
  double lo = INFINITY, hi = -INFINITY;
  for (float v : map.values())
    if (std::isfinite(v))
    {
      lo = std::min(lo, static_cast<double>(v));
      hi = std::max(hi, static_cast<double>(v));
    }
  if (!std::isfinite(lo))
    return {};
  RangeMapImageEncoding e;
  e.offsetMm = lo;
  e.stepMm = hi > lo ? (hi - lo) / 65534.0 : 1e-3;
  return e;
}

void writeRangeMapPng(const RangeMap& map, const std::string& path, const RangeMapImageEncoding& encoding)
{
  if (!(encoding.stepMm > 0.0) || !std::isfinite(encoding.offsetMm))
    throw std::invalid_argument("range map image encoding needs a positive step and a finite offset");
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(map.nTheta(), map.nZ(), 1);
  image->AllocateScalars(VTK_UNSIGNED_SHORT, 1);
  auto* g = static_cast<std::uint16_t*>(image->GetScalarPointer());
  // VTK images start at the bottom row, as the map's row 0 (inferior).
  for (std::size_t k = 0; k < map.values().size(); ++k)
  {
    const float r = map.values()[k];
    g[k] = std::isfinite(r) ? static_cast<std::uint16_t>(
                                std::clamp(std::llround((r - encoding.offsetMm) / encoding.stepMm) + 1, 1LL, 65535LL))
                            : std::uint16_t{0};
  }
  const CylindricalFrame& f = map.frame();
  writePng(image, path,
           {{kOffset, number(encoding.offsetMm)},
            {kStep, number(encoding.stepMm)},
            {kOrigin, vector3(f.origin())},
            {kDirection, vector3(f.direction())},
            {kZRange, number(f.zMin()) + " " + number(f.zMax())}});
}

RangeMapImageEncoding writeRangeMapPng(const RangeMap& map, const std::string& path)
{
  const RangeMapImageEncoding e = rangeMapImageEncoding(map);
  writeRangeMapPng(map, path, e);
  return e;
}

RangeMapImageEncoding readRangeMapImageEncoding(const std::string& path)
{
  const PngContents png = readPng(path);
  return {parseNumber(png.text, kOffset, path), parseNumber(png.text, kStep, path)};
}

namespace {
RangeMap decodeRange(const PngContents& png, const CylindricalFrame& frame, const RangeMapImageEncoding& e,
                     const std::string& path)
{
  checkSize(png.image, frame, path);
  RangeMap map(frame);
  vtkDataArray* scalars = png.image->GetPointData()->GetScalars();
  for (vtkIdType k = 0; k < scalars->GetNumberOfTuples(); ++k)
  {
    const double g = scalars->GetComponent(k, 0);
    map.values()[static_cast<std::size_t>(k)] =
      g > 0.0 ? static_cast<float>(e.offsetMm + e.stepMm * (g - 1.0)) : RangeMap::quietNaN();
  }
  return map;
}
} // namespace

RangeMap readRangeMapPng(const std::string& path, const CylindricalFrame& frame, const RangeMapImageEncoding& encoding)
{
  return decodeRange(readPng(path), frame, encoding, path);
}

RangeMap readRangeMapPng(const std::string& path)
{
  const PngContents png = readPng(path);
  const RangeMapImageEncoding e{parseNumber(png.text, kOffset, path), parseNumber(png.text, kStep, path)};
  const Eigen::Vector3d origin = parseVector(png.text, kOrigin, path);
  const Eigen::Vector3d direction = parseVector(png.text, kDirection, path);
  double zMin = 0.0, zMax = 0.0;
  const auto it = png.text.find(kZRange);
  if (it == png.text.end() || std::sscanf(it->second.c_str(), "%lf %lf", &zMin, &zMax) != 2)
    throw std::runtime_error(std::string("the range map image ") + path + " has lost its '" + kZRange +
                             "' text chunk: read it with a known frame and encoding");
  int dims[3];
  png.image->GetDimensions(dims);
  const CylindricalFrame frame(origin, direction, zMin, zMax, dims[0], dims[1]);
  return decodeRange(png, frame, e, path);
}

void writeColourMapPng(const ColourMap& map, const std::string& path)
{
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(map.nTheta(), map.nZ(), 1);
  image->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
  auto* p = static_cast<std::uint8_t*>(image->GetScalarPointer());
  for (std::size_t k = 0; k < map.values().size(); ++k)
    for (std::size_t c = 0; c < 3; ++c)
      p[3 * k + c] = map.values()[k][c];
  writePng(image, path, {});
}

ColourMap readColourMapPng(const std::string& path, const CylindricalFrame& frame)
{
  const PngContents png = readPng(path);
  checkSize(png.image, frame, path);
  ColourMap map(frame);
  vtkDataArray* scalars = png.image->GetPointData()->GetScalars();
  const int nc = scalars->GetNumberOfComponents();
  // 16-bit colour PNGs are scaled down to 8 bits.
  const double scale = scalars->GetDataType() == VTK_UNSIGNED_SHORT ? 255.0 / 65535.0 : 1.0;
  for (vtkIdType k = 0; k < scalars->GetNumberOfTuples(); ++k)
    for (int c = 0; c < 3; ++c)
    {
      const double v = scalars->GetComponent(k, nc >= 3 ? c : 0) * scale;
      map.values()[static_cast<std::size_t>(k)][static_cast<std::size_t>(c)] =
        static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
    }
  return map;
}

} // namespace caps::seg
