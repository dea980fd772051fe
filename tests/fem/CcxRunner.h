#pragma once
// Running CalculiX (ccx, Debian package calculix-ccx) on a deck for the
// comparison tests: one runner for every test file that checks against it.

#include "fem/CalculixIO.h"

#include <Eigen/Core>

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>

namespace caps::fem::test {

inline bool ccxAvailable()
{
  return std::system("command -v ccx > /dev/null 2>&1") == 0;
}

/// Displacements ccx computed, per node (columns): from the .dat (7
/// significant digits) and the .frd (6 digits; empty unless asked for).
struct CcxResult
{
  Eigen::Matrix3Xd dat, frd;
};

/// Writes @a deck into a fresh temporary folder and runs "ccx -i job" there
/// (one thread); throws std::runtime_error with the end of ccx's log when it
/// fails. The folder is removed unless CAPS_KEEP_CCX is set.
inline CcxResult runCcx(const std::string& name, const std::string& deck, Eigen::Index nodeCount, bool readFrd = false)
{
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("caps_ccx_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "job.inp") << deck;
  const std::string cmd = "cd '" + dir.string() + "' && OMP_NUM_THREADS=1 ccx -i job > ccx.log 2>&1";
  if (std::system(cmd.c_str()) != 0 || !fs::exists(dir / "job.dat") || (readFrd && !fs::exists(dir / "job.frd")))
  {
    std::ifstream log(dir / "ccx.log");
    const std::string text((std::istreambuf_iterator<char>(log)), std::istreambuf_iterator<char>());
    throw std::runtime_error("ccx failed on " + (dir / "job.inp").string() + ":\n" +
                             text.substr(text.size() > 3000 ? text.size() - 3000 : 0));
  }
  CcxResult r;
  r.dat = readDatDisplacements((dir / "job.dat").string(), nodeCount);
  if (readFrd)
    r.frd = readFrdDisplacements((dir / "job.frd").string(), nodeCount);
  if (!std::getenv("CAPS_KEEP_CCX"))
    fs::remove_all(dir);
  return r;
}

/// max |ccx - ours| / max |ours| over the nodes ccx reported.
inline double relativeDifference(const Eigen::Matrix3Xd& ccx, const Eigen::VectorXd& ours)
{
  const Eigen::Map<const Eigen::VectorXd> flat(ccx.data(), ccx.size());
  return (flat - ours.head(flat.size())).cwiseAbs().maxCoeff() / ours.cwiseAbs().maxCoeff();
}

} // namespace caps::fem::test
