#pragma once
// Skins whose lengths, angles and areas are known in closed form.

#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "planning/PlanSimulation.h"
#include "planning/ProcedureTemplate.h"
#include "segmentation/RangeMap.h"

namespace caps::test {

inline constexpr double pi = 3.14159265358979323846;
inline constexpr double degree = pi / 180.0;

/// A cylinder of radius R about the frame's axis: r(θ, z) = R.
inline seg::RangeMap cylinderSkin(double radius, double zMin = -100.0, double zMax = 100.0)
{
  return seg::RangeMap(seg::CylindricalFrame({0, 0, 0}, {0, 0, 1}, zMin, zMax, 720, 401), float(radius));
}

/// A sphere of radius ρ centred on the axis at z = 0, scanned over |z| ≤ 0.8 ρ
/// with rows 0.05 mm apart (bilinear reading between rows is then exact to ~1e-6).
inline seg::RangeMap sphereSkin(double rho)
{
  const double zMax = 0.8 * rho;
  const int nz = int(std::lround(2.0 * zMax / 0.05)) + 1;
  seg::RangeMap map(seg::CylindricalFrame({0, 0, 0}, {0, 0, 1}, -zMax, zMax, 360, nz));
  for (int j = 0; j < nz; ++j)
  {
    const double z = map.frame().indexToZ(j);
    for (int i = 0; i < map.nTheta(); ++i)
      map.at(i, j) = float(std::sqrt(rho * rho - z * z));
  }
  return map;
}

/// The simulation phantom: skin r = 80 mm over bone r = 70 mm (10 mm of soft tissue).
struct CylinderPhantom
{
  seg::RangeMap skin = cylinderSkin(80.0);
  seg::RangeMap bone = cylinderSkin(70.0);
};

inline const CylinderPhantom& cylinderPhantom()
{
  static const CylinderPhantom p;
  return p;
}

/// The phantom tests' simulation: 2 mm elements, a 20 mm region, 3 layers, one thread.
inline planning::SimulationOptions phantomSimulationOptions()
{
  planning::SimulationOptions o;
  o.elementSize = 2.0;
  o.regionRadius = 20.0;
  o.layerCount = 3;
  // Through every layer to the bone: the thesis's model (§4.5.2), which the
  // phantom tests check against; the tests of the procedures' own depth say so.
  o.cutLayers = 0;
  o.threads = 1;
  return o;
}

inline std::filesystem::path proceduresFolder()
{
  return std::filesystem::path(CAPS_TEST_DATA_DIR) / "procedures";
}

inline const planning::ProcedureLibrary& shippedProcedures()
{
  static const planning::ProcedureLibrary library = planning::ProcedureLibrary::load(proceduresFolder());
  return library;
}

/// The shipped procedure @a id (data/procedures/); throws when there is none.
inline const planning::ProcedureTemplate& shippedProcedure(const std::string& id)
{
  const planning::ProcedureTemplate* t = shippedProcedures().find(id);
  if (!t)
    throw std::runtime_error("no procedure " + id);
  return *t;
}

} // namespace caps::test
