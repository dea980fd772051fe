#include "render/ColourMaps.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <vtkLookupTable.h>

namespace caps::render {
namespace {

/// Control points of the colour maps, evenly spaced in [0, 1].
const std::vector<Rgb>& controlPoints(ColourMap map)
{
  // matplotlib's viridis at 0, 1/8, …, 1.
  static const std::vector<Rgb> viridis{{0.267004, 0.004874, 0.329415}, {0.282623, 0.140926, 0.457517},
                                        {0.229739, 0.322361, 0.545706}, {0.172719, 0.448791, 0.557885},
                                        {0.127568, 0.566949, 0.550556}, {0.134692, 0.658636, 0.517649},
                                        {0.266941, 0.748751, 0.440573}, {0.477504, 0.821444, 0.318195},
                                        {0.741388, 0.873449, 0.149561}, {0.993248, 0.906157, 0.143936}};
  // Moreland's cool-warm (2009) at 0, 1/8, …, 1.
  static const std::vector<Rgb> coolWarm{{0.230, 0.299, 0.754}, {0.348, 0.466, 0.888}, {0.484, 0.622, 0.975},
                                         {0.619, 0.744, 0.999}, {0.865, 0.865, 0.865}, {0.958, 0.770, 0.677},
                                         {0.958, 0.604, 0.482}, {0.897, 0.424, 0.328}, {0.706, 0.016, 0.150}};
  // ColorBrewer YlGnBu (9 classes) without its near-white first class.
  static const std::vector<Rgb> thickness{
    {0xed / 255.0, 0xf8 / 255.0, 0xb1 / 255.0}, {0xc7 / 255.0, 0xe9 / 255.0, 0xb4 / 255.0},
    {0x7f / 255.0, 0xcd / 255.0, 0xbb / 255.0}, {0x41 / 255.0, 0xb6 / 255.0, 0xc4 / 255.0},
    {0x1d / 255.0, 0x91 / 255.0, 0xc0 / 255.0}, {0x22 / 255.0, 0x5e / 255.0, 0xa8 / 255.0},
    {0x25 / 255.0, 0x34 / 255.0, 0x94 / 255.0}, {0x08 / 255.0, 0x1d / 255.0, 0x58 / 255.0}};
  switch (map)
  {
  case ColourMap::CoolWarm:
    return coolWarm;
  case ColourMap::Thickness:
    return thickness;
  case ColourMap::Viridis:
    break;
  }
  return viridis;
}

} // namespace

Rgb colourMapColour(ColourMap map, double t)
{
  const std::vector<Rgb>& points = controlPoints(map);
  if (!std::isfinite(t))
    t = 0.0;
  const double x = std::clamp(t, 0.0, 1.0) * double(points.size() - 1);
  const std::size_t i = std::min(std::size_t(x), points.size() - 2);
  const double f = x - double(i);
  Rgb c;
  for (std::size_t k = 0; k < 3; ++k)
    c[k] = (1.0 - f) * points[i][k] + f * points[i + 1][k];
  return c;
}

vtkSmartPointer<vtkLookupTable> colourMapLookupTable(ColourMap map, const std::array<double, 2>& range)
{
  auto table = vtkSmartPointer<vtkLookupTable>::New();
  constexpr int n = 256;
  table->SetNumberOfTableValues(n);
  for (int i = 0; i < n; ++i)
  {
    const Rgb c = colourMapColour(map, double(i) / (n - 1));
    table->SetTableValue(i, c[0], c[1], c[2], 1.0);
  }
  table->SetRange(range[0], range[1]);
  table->SetNanColor(0.62, 0.62, 0.62, 1.0);
  return table;
}

std::string colourMapName(ColourMap map)
{
  switch (map)
  {
  case ColourMap::CoolWarm:
    return "cool-warm";
  case ColourMap::Thickness:
    return "thickness";
  case ColourMap::Viridis:
    break;
  }
  return "viridis";
}

std::optional<ColourMap> colourMapFromName(const std::string& name)
{
  for (ColourMap map : {ColourMap::CoolWarm, ColourMap::Viridis, ColourMap::Thickness})
    if (colourMapName(map) == name)
      return map;
  return std::nullopt;
}

} // namespace caps::render
