#include "fem/BlasKernels.h"

#include <dlfcn.h>
#include <unistd.h>

#include <array>
#include <cstdlib>
#include <string_view>

namespace caps::fem {

std::string blasCoreName()
{
  // Looked up at run time: CHOLMOD links whichever libblas.so.3 the system
  // selects (OpenBLAS or the reference BLAS), so we cannot link to OpenBLAS's API.
  using CoreName = char* (*)();
  const auto get = reinterpret_cast<CoreName>(dlsym(RTLD_DEFAULT, "openblas_get_corename"));
  if (!get)
    return {};
  const char* name = get();
  return name ? std::string(name) : std::string();
}

std::string betterBlasCoreType()
{
#if defined(__x86_64__)
  const std::string core = blasCoreName();
  // OpenBLAS's x86-64 kernel sets without AVX2: what it falls back to when
  // it does not recognise a newer CPU.
  constexpr std::array<std::string_view, 12> generic = {"Prescott",   "Core2",     "Penryn",      "Dunnington",
                                                        "Nehalem",    "Atom",      "Sandybridge", "Katmai",
                                                        "Coppermine", "Northwood", "Banias",      "Barcelona"};
  bool fallback = false;
  for (std::string_view g : generic)
    if (core == g)
      fallback = true;
  if (!fallback)
    return {};
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512bw") &&
      __builtin_cpu_supports("avx512vl"))
    return "SkylakeX";
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"))
    return "Haswell";
#endif
  return {};
}

void useBestBlasKernels(char** argv)
{
  if (!argv || std::getenv("OPENBLAS_CORETYPE"))
    return; // the user's choice, or we re-executed already
  const std::string better = betterBlasCoreType();
  if (better.empty())
    return;
  if (setenv("OPENBLAS_CORETYPE", better.c_str(), 1) != 0)
    return;
  execv("/proc/self/exe", argv);
  unsetenv("OPENBLAS_CORETYPE"); // exec failed: carry on as we are
}

} // namespace caps::fem
