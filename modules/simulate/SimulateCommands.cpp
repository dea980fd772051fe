#include "modules/simulate/SimulateCommands.h"

#include <cstdlib>
#include <iomanip>
#include <iostream>

#include "modules/simulate/SimulateLogic.h"

namespace fs = std::filesystem;

namespace caps {
namespace {

const char* kFemUsage =
  "usage: caps fem MODEL.inp [--out DIR] [--threads N] [--quiet]\n"
  "\n"
  "Solves a static CalculiX/Abaqus input deck with the CAPS finite element core and writes into\n"
  "DIR (default: the current folder):\n"
  "  displacements.csv  node, x, y, z, ux, uy, uz (mm)\n"
  "  stresses.csv       node, sxx, syy, szz, sxy, syz, szx, von Mises (MPa, averaged at nodes;\n"
  "                     Cauchy stress in a large-deformation step)\n"
  "  gauss_stresses.csv element, point, sxx, syy, szz, sxy, sxz, syz (MPa, at each element's\n"
  "                     integration points, in the order and columns of ccx's *EL PRINT S)\n"
  "  result.vtu         the mesh with displacement and stress fields (and det F and the largest\n"
  "                     stretch in large deformation), for ParaView\n"
  "  increments.csv     large deformation: every increment tried (load fractions, Newton\n"
  "                     iterations, residual, accepted or why it was cut back)\n"
  "\n"
  "Large deformation: *STEP, NLGEOM (or any *HYPERELASTIC material, which CalculiX solves\n"
  "nonlinearly too) is solved in Total Lagrangian form by Newton-Raphson with a line search;\n"
  "an iteration keeps the last factorization when that is measured to converge sooner.\n"
  "*STATIC's data line (initial increment, step time, minimum, maximum) sets the increments:\n"
  "they grow after a fast convergence and are cut back when Newton fails or an element would\n"
  "turn inside out (det F <= 0); *STATIC, DIRECT keeps them fixed. Loads, prescribed\n"
  "displacements and *EQUATION offsets (suture gaps) are ramped together. Materials:\n"
  "*HYPERELASTIC, NEO HOOKE (C10, D1: U = C10 (I1b - 3) + (J - 1)^2 / D1) and MOONEY-RIVLIN\n"
  "(C10, C01, D1), the forms CalculiX uses; *ELASTIC is St. Venant-Kirchhoff, as in CalculiX.\n"
  "Face pressure (a follower load) is refused in large deformation. A step that does not\n"
  "converge writes only increments.csv and says where it stopped; it is never a result.\n"
  "\n"
  "Supported: *NODE, *ELEMENT (C3D20, C3D20R with its reduced 2x2x2 integration, C3D15 with\n"
  "CalculiX's 9-point rule, C3D8), *NSET, *ELSET (set names may start with a digit), *MATERIAL,\n"
  "*ELASTIC, *HYPERELASTIC, *DENSITY, *SOLID SECTION, *BOUNDARY, *CLOAD, *DLOAD GRAV and face\n"
  "pressure P1..P6, *EQUATION (any number of terms), *STEP (NLGEOM), *STATIC; *CONTROLS,\n"
  "*ORIENTATION and *EXPANSION (no effect on isotropic materials without temperatures) and\n"
  "output requests are ignored. Anything else is an error.\n"
  "\n"
  "Exit status: 0 when solved, 1 when the model cannot be read or solved (or a large-deformation\n"
  "step did not converge), 2 on wrong usage.\n";

int runFem(ModuleLogic&, const std::vector<std::string>& args, std::ostream& out, std::ostream& err)
{
  fs::path deck, outDir = ".";
  FemRunOptions options;
  bool quiet = false;
  for (size_t i = 0; i < args.size(); ++i)
  {
    const std::string& a = args[i];
    if (a == "--help" || a == "-h")
    {
      out << kFemUsage;
      return 0;
    }
    if (a == "--quiet")
    {
      quiet = true;
      continue;
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
      err << "caps fem: one MODEL only (got '" << deck.string() << "' and '" << a << "')\n" << kFemUsage;
      return 2;
    }
  }
  if (deck.empty())
  {
    err << "caps fem: MODEL.inp missing\n" << kFemUsage;
    return 2;
  }
  // Large deformation: a line per Newton iteration, as it goes.
  if (!quiet)
    options.progress = [&out](const fem::NewtonIteration& it) {
      out << "increment " << it.increment << " to load fraction " << std::setprecision(6) << it.loadFraction
          << ", iteration " << it.iteration << ": residual " << std::setprecision(3) << it.residual << ", energy "
          << it.energy << (it.lineSearchStep < 1.0 ? ", line search " : "")
          << (it.lineSearchStep < 1.0 ? std::to_string(it.lineSearchStep) : std::string())
          << (it.newTangent ? "" : " (factorization kept)") << "\n"
          << std::flush;
    };
  const FemRunReport r = SimulateLogic::solveDeck(deck, outDir, options);
  if (r.status != FemRunStatus::Success)
  {
    err << "caps fem: " << r.message << "\n";
    return 1;
  }
  out << "model: " << r.nodes << " nodes, " << r.elements << " elements, " << r.dofs << " DOF\n"
      << std::fixed << std::setprecision(4) << "time (s): read " << r.readSeconds;
  if (r.largeDeformation)
    out << ", Newton solve " << r.times.factor;
  else
    out << ", assemble " << r.times.assemble << ", constrain " << r.times.constrain << ", analyse " << r.times.analyse
        << ", factor " << r.times.factor << ", solve " << r.times.solve;
  out << ", stresses " << r.recoverSeconds << ", write " << r.writeSeconds << "\n"
      << std::defaultfloat << std::setprecision(6) << "max displacement: " << r.maxDisplacement << " mm at node "
      << r.maxDisplacementNode << "\n"
      << "max von Mises stress: " << r.maxVonMises << " MPa" << (r.largeDeformation ? " (Cauchy)" : "") << "\n";
  if (r.largeDeformation)
    out << "large deformation: " << r.increments << " increments, " << r.iterations
        << " Newton iterations; smallest det F " << r.check.minDetF << ", largest stretch " << r.check.maxStretch
        << ", smallest stretch " << r.check.minStretch << "\n";
  for (const auto& f : r.files)
    out << "wrote " << f.string() << "\n";
  return 0;
}

} // namespace

std::vector<ModuleCommand> simulateCommands()
{
  return {{"fem", "solve a CalculiX/Abaqus .inp deck; write displacements, stresses and a VTU", kFemUsage, runFem}};
}

} // namespace caps
