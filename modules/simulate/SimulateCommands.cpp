#include "modules/simulate/SimulateCommands.h"

#include <cstdlib>
#include <iomanip>
#include <iostream>

#include "modules/simulate/SimulateLogic.h"

namespace fs = std::filesystem;

namespace caps {
namespace {

const char* kFemUsage =
  "usage: caps fem MODEL.inp [--out DIR] [--threads N]\n"
  "\n"
  "Solves a linear static CalculiX/Abaqus input deck with the CAPS finite element\n"
  "core and writes into DIR (default: the current folder):\n"
  "  displacements.csv  node, x, y, z, ux, uy, uz (mm)\n"
  "  stresses.csv       node, sxx, syy, szz, sxy, syz, szx, von Mises (MPa, averaged at nodes)\n"
  "  gauss_stresses.csv element, point, sxx, syy, szz, sxy, sxz, syz (MPa, at each element's\n"
  "                     integration points, in the order and columns of ccx's *EL PRINT S)\n"
  "  result.vtu         the mesh with displacement and stress fields, for ParaView\n"
  "\n"
  "Supported: *NODE, *ELEMENT (C3D20, C3D20R with its reduced 2x2x2 integration, C3D15, C3D8),\n"
  "*NSET, *ELSET (set names may start with a digit), *MATERIAL, *ELASTIC, *HYPERELASTIC (NEO HOOKE,\n"
  "MOONEY-RIVLIN; read, not yet solved), *DENSITY, *SOLID SECTION, *BOUNDARY, *CLOAD, *DLOAD GRAV and\n"
  "face pressure P1..P6, *EQUATION (any number of terms), *STEP (NLGEOM read, not yet solved),\n"
  "*STATIC; *CONTROLS, *ORIENTATION and *EXPANSION (no effect on isotropic materials without\n"
  "temperatures) and output requests are ignored. Anything else is an error.\n"
  "\n"
  "Exit status: 0 when solved, 1 when the model cannot be read or solved, 2 on wrong usage.\n";

int runFem(ModuleLogic&, const std::vector<std::string>& args, std::ostream& out, std::ostream& err)
{
  fs::path deck, outDir = ".";
  FemRunOptions options;
  for (size_t i = 0; i < args.size(); ++i)
  {
    const std::string& a = args[i];
    if (a == "--help" || a == "-h")
    {
      out << kFemUsage;
      return 0;
    }
    if (a == "--out" || a == "--threads")
    {
      if (i + 1 >= args.size())
      {
        err << "caps fem: " << a << " needs a value\n" << kFemUsage;
        return 2;
      }
      const std::string v = args[++i];
      if (a == "--out")
        outDir = v;
      else
      {
        char* end = nullptr;
        const long n = std::strtol(v.c_str(), &end, 10);
        if (v.empty() || *end || n < 1 || n > 256)
        {
          err << "caps fem: --threads needs a number from 1 to 256\n" << kFemUsage;
          return 2;
        }
        options.threads = int(n);
      }
    }
    else if (!a.empty() && a[0] == '-')
    {
      err << "caps fem: unknown option " << a << "\n" << kFemUsage;
      return 2;
    }
    else if (deck.empty())
      deck = a;
    else
    {
      err << "caps fem: one MODEL only (got '" << deck.string() << "' and '" << a << "')\n"
          << kFemUsage;
      return 2;
    }
  }
  if (deck.empty())
  {
    err << "caps fem: MODEL.inp missing\n" << kFemUsage;
    return 2;
  }
  const FemRunReport r = SimulateLogic::solveDeck(deck, outDir, options);
  if (r.status != FemRunStatus::Success)
  {
    err << "caps fem: " << r.message << "\n";
    return 1;
  }
  out << "model: " << r.nodes << " nodes, " << r.elements << " elements, " << r.dofs << " DOF\n"
      << std::fixed << std::setprecision(4) << "time (s): read " << r.readSeconds << ", assemble "
      << r.times.assemble << ", constrain " << r.times.constrain << ", analyse " << r.times.analyse
      << ", factor " << r.times.factor << ", solve " << r.times.solve << ", stresses "
      << r.recoverSeconds << ", write " << r.writeSeconds << "\n"
      << std::defaultfloat << std::setprecision(6) << "max displacement: " << r.maxDisplacement
      << " mm at node " << r.maxDisplacementNode << "\n"
      << "max von Mises stress: " << r.maxVonMises << " MPa\n";
  for (const auto& f : r.files)
    out << "wrote " << f.string() << "\n";
  return 0;
}

} // namespace

std::vector<ModuleCommand> simulateCommands()
{
  return {{"fem", "solve a CalculiX/Abaqus .inp deck; write displacements, stresses and a VTU",
           kFemUsage, runFem}};
}

} // namespace caps
