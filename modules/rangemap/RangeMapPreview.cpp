#include "modules/rangemap/RangeMapPreview.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>
#include <vector>

#include <vtkFreeTypeTools.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkStdString.h>
#include <vtkTextProperty.h>

namespace caps {
namespace {

/// An RGB picture, row 0 at the bottom.
class Canvas
{
public:
  Canvas(int width, int height) : width_(width), height_(height), rgb_(3ull * width * height, 255) {}
  int width() const { return width_; }
  int height() const { return height_; }

  void set(int x, int y, const unsigned char c[3])
  {
    if (x < 0 || y < 0 || x >= width_ || y >= height_)
      return;
    std::copy(c, c + 3, &rgb_[3 * (static_cast<std::size_t>(y) * width_ + x)]);
  }
  void blend(int x, int y, const unsigned char c[3], double alpha)
  {
    if (x < 0 || y < 0 || x >= width_ || y >= height_)
      return;
    unsigned char* p = &rgb_[3 * (static_cast<std::size_t>(y) * width_ + x)];
    for (int a = 0; a < 3; ++a)
      p[a] = static_cast<unsigned char>(std::lround(p[a] * (1 - alpha) + c[a] * alpha));
  }
  void fill(int x0, int y0, int x1, int y1, const unsigned char c[3])
  {
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x)
        set(x, y, c);
  }
  /// Outline of the box [x0, x1) × [y0, y1), one pixel outside it.
  void frame(int x0, int y0, int x1, int y1, const unsigned char c[3])
  {
    for (int x = x0 - 1; x <= x1; ++x)
    {
      set(x, y0 - 1, c);
      set(x, y1, c);
    }
    for (int y = y0 - 1; y <= y1; ++y)
    {
      set(x0 - 1, y, c);
      set(x1, y, c);
    }
  }

  /// Draws text; (x, y) is the anchor, placed by the horizontal (0 left,
  /// 1 centre, 2 right) and vertical (0 bottom, 1 centre, 2 top) alignment.
  void text(const std::string& s, int x, int y, int size, int hAlign, int vAlign, bool bold = false)
  {
    vtkNew<vtkTextProperty> property;
    property->SetFontFamilyToArial();
    property->SetFontSize(size);
    property->SetBold(bold);
    property->SetColor(0.0, 0.0, 0.0);
    property->SetJustificationToLeft();
    property->SetVerticalJustificationToBottom();
    vtkNew<vtkImageData> image;
    int dims[2] = {0, 0};
    if (!vtkFreeTypeTools::GetInstance()->RenderString(property.GetPointer(), vtkStdString(s), 72, image.GetPointer(),
                                                       dims))
      return; // no text rather than no picture
    int extent[6];
    image->GetExtent(extent);
    const int w = dims[0], h = dims[1];
    const int left = x - (hAlign == 1 ? w / 2 : hAlign == 2 ? w : 0);
    const int bottom = y - (vAlign == 1 ? h / 2 : vAlign == 2 ? h : 0);
    const int components = image->GetNumberOfScalarComponents();
    const unsigned char black[3] = {0, 0, 0};
    for (int iy = extent[2]; iy <= extent[3]; ++iy)
      for (int ix = extent[0]; ix <= extent[1]; ++ix)
      {
        const auto* p = static_cast<const unsigned char*>(image->GetScalarPointer(ix, iy, 0));
        const double alpha = (components == 4 ? p[3] : p[0]) / 255.0;
        if (alpha > 0)
          blend(left + ix - extent[0], bottom + iy - extent[2], black, alpha);
      }
  }

  vtkSmartPointer<vtkImageData> toImage() const
  {
    auto image = vtkSmartPointer<vtkImageData>::New();
    image->SetDimensions(width_, height_, 1);
    image->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
    std::copy(rgb_.begin(), rgb_.end(), static_cast<unsigned char*>(image->GetScalarPointer()));
    return image;
  }

private:
  int width_, height_;
  std::vector<unsigned char> rgb_;
};

/// A "nice" tick step (1, 2 or 5 × 10^k) giving about @a count ticks over @a span.
double niceStep(double span, int count)
{
  const double raw = span / std::max(1, count);
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * magnitude >= raw)
      return m * magnitude;
  return 10.0 * magnitude;
}

std::string formatTick(double value, double step)
{
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, step < 1.0 ? "%.1f" : "%.0f", value);
  std::string s = buffer;
  return s == "-0" ? "0" : s;
}

} // namespace

void viridis(double t, unsigned char rgb[3])
{
  // Viridis (van der Walt and Smith, matplotlib 2015) at t = 0, 0.1, ..., 1.
  static const unsigned char table[11][3] = {{68, 1, 84},    {72, 36, 117},  {65, 68, 135},  {53, 95, 141},
                                             {42, 120, 142}, {33, 145, 140}, {34, 168, 132}, {68, 191, 112},
                                             {122, 209, 81}, {189, 223, 38}, {253, 231, 37}};
  const double x = std::clamp(t, 0.0, 1.0) * 10.0;
  const int k = std::min(9, static_cast<int>(x));
  const double f = x - k;
  for (int a = 0; a < 3; ++a)
    rgb[a] = static_cast<unsigned char>(std::lround(table[k][a] * (1 - f) + table[k + 1][a] * f));
}

vtkSmartPointer<vtkImageData> renderRangeMapPreview(const Eigen::MatrixXf& values, double zMin, double zMax,
                                                    const PreviewStyle& style)
{
  const int nTheta = static_cast<int>(values.rows());
  const int nZ = static_cast<int>(values.cols());
  if (nTheta < 1 || nZ < 2 || !(zMax > zMin) || !(style.high > style.low))
    throw std::invalid_argument("Cannot draw an empty range map or an empty value range.");
  const int s = std::max(1, style.pixelsPerSample);
  // Text, margins and ticks grow with textScale, so a map drawn large for
  // print keeps labels of a readable printed size.
  const double scale = std::max(0.25, style.textScale);
  const auto px = [scale](double pixels) { return static_cast<int>(std::lround(pixels * scale)); };
  const int mapW = nTheta * s, mapH = nZ * s;
  const int left = px(70), right = px(110), bottom = px(56), top = px(46);
  Canvas canvas(left + mapW + right, bottom + mapH + top);
  const unsigned char black[3] = {0, 0, 0};
  const unsigned char grey[3] = {150, 150, 150};

  // The map: picture column x shows θ = -3π/2 + 2π (x + 0.5) / mapW, so the
  // face (-π/2) is in the middle and the back (π/2) at both edges.
  for (int x = 0; x < mapW; ++x)
  {
    const double u = (x + 0.5) / mapW * nTheta - 0.25 * nTheta; // sample column of θ
    const int i = ((static_cast<int>(std::floor(u + 0.5)) % nTheta) + nTheta) % nTheta;
    for (int y = 0; y < mapH; ++y)
    {
      const int j = std::min(nZ - 1, y / s);
      const float v = values(i, j);
      unsigned char c[3];
      if (std::isfinite(v))
        viridis((v - style.low) / (style.high - style.low), c);
      else
        std::copy(grey, grey + 3, c);
      canvas.set(left + x, bottom + y, c);
    }
  }
  canvas.frame(left, bottom, left + mapW, bottom + mapH, black);

  // Directions below the map (facing the patient: patient right on the left).
  const char* directions[5] = {"back", "right", "face", "left", "back"};
  for (int q = 0; q <= 4; ++q)
  {
    const int x = left + q * mapW / 4;
    canvas.fill(x, bottom - px(6), x + 1, bottom - 1, black);
    canvas.text(directions[q], x, bottom - px(8), px(14), 1, 2);
  }
  canvas.text("around the head (theta)", left + mapW / 2, px(6), px(13), 1, 0);

  // z ticks on the left.
  const double zStep = niceStep(zMax - zMin, 6);
  for (double z = std::ceil(zMin / zStep) * zStep; z <= zMax + 1e-9; z += zStep)
  {
    const int y = bottom + static_cast<int>(std::lround((z - zMin) / (zMax - zMin) * (mapH - 1)));
    canvas.fill(left - px(6), y, left - 1, y + std::max(1, px(1)), black);
    canvas.text(formatTick(z, zStep), left - px(9), y, px(13), 2, 1);
  }
  canvas.text("z (mm)", px(4), bottom + mapH + px(8), px(13), 0, 0);

  // Title.
  canvas.text(style.title, left, bottom + mapH + px(12), px(18), 0, 0, true);

  // Colour bar on the right.
  const int barX = left + mapW + px(24), barW = px(22), barH = mapH;
  for (int y = 0; y < barH; ++y)
  {
    unsigned char c[3];
    viridis((y + 0.5) / barH, c);
    canvas.fill(barX, bottom + y, barX + barW, bottom + y + 1, c);
  }
  canvas.frame(barX, bottom, barX + barW, bottom + barH, black);
  const double step = niceStep(style.high - style.low, 6);
  for (double v = std::ceil(style.low / step - 1e-9) * step; v <= style.high + 1e-9; v += step)
  {
    const int y = bottom + static_cast<int>(std::lround((v - style.low) / (style.high - style.low) * (barH - 1)));
    canvas.fill(barX + barW, y, barX + barW + px(5), y + std::max(1, px(1)), black);
    canvas.text(formatTick(v, step), barX + barW + px(8), y, px(13), 0, 1);
  }
  canvas.text(style.unit, barX + barW / 2, bottom + barH + px(8), px(14), 1, 0, true);
  // The grey of "no surface found".
  canvas.fill(barX, bottom - px(40), barX + barW, bottom - px(26), grey);
  canvas.frame(barX, bottom - px(40), barX + barW, bottom - px(26), black);
  canvas.text("none", barX + barW + px(6), bottom - px(33), px(12), 0, 1);
  return canvas.toImage();
}

void writeRangeMapPreview(const Eigen::MatrixXf& values, double zMin, double zMax, const PreviewStyle& style,
                          const std::filesystem::path& file)
{
  auto image = renderRangeMapPreview(values, zMin, zMax, style);
  vtkNew<vtkPNGWriter> writer;
  writer->SetInputData(image);
  writer->SetFileName(file.string().c_str());
  writer->Write();
  if (writer->GetErrorCode() != 0)
    throw std::runtime_error("Could not write " + file.string() + ": is the folder writable?");
}

PreviewStyle rangeStyle(const Eigen::MatrixXf& values, std::string title)
{
  std::vector<float> finite;
  finite.reserve(static_cast<std::size_t>(values.size()));
  for (Eigen::Index k = 0; k < values.size(); ++k)
    if (std::isfinite(values.data()[k]))
      finite.push_back(values.data()[k]);
  PreviewStyle style;
  style.title = std::move(title);
  style.low = 0.0;
  style.high = 100.0;
  if (!finite.empty())
  {
    auto at = [&finite](double percent) {
      const auto k = static_cast<std::size_t>(std::lround(percent / 100.0 * double(finite.size() - 1)));
      std::nth_element(finite.begin(), finite.begin() + static_cast<std::ptrdiff_t>(k), finite.end());
      return double(finite[k]);
    };
    style.low = 10.0 * std::floor(at(2.0) / 10.0);
    style.high = 10.0 * std::ceil(at(98.0) / 10.0);
  }
  if (style.high <= style.low)
    style.high = style.low + 10.0;
  return style;
}

} // namespace caps
