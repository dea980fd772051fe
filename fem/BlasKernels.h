#pragma once
/// @file BlasKernels.h
/// @brief Making sure the BLAS under CHOLMOD runs the kernels the CPU can
/// run: the supernodal factorization spends most of its time in dgemm/dsyrk.

#include <string>

namespace caps::fem {

/// The kernels OpenBLAS picked ("SkylakeX", "Haswell", "Prescott", ...), or
/// "" when the BLAS in the process is not OpenBLAS.
std::string blasCoreName();

/// The OpenBLAS kernels this CPU should run when OpenBLAS fell back to an
/// old generic set, or "" when nothing needs changing.
///
/// OpenBLAS 0.3.21 (Debian 12) chooses kernels by the CPU's model number; on
/// CPUs newer than it knows (Sapphire/Emerald Rapids, recent cores) it falls
/// back to Prescott (SSE3) kernels, about 6x slower in dgemm on this project's
/// machines (OpenBLAS issue #4267). Judged by what the CPU supports: AVX-512
/// (F, DQ, BW, VL) gives "SkylakeX", AVX2 with FMA "Haswell".
std::string betterBlasCoreType();

/// OpenBLAS reads its only switch, OPENBLAS_CORETYPE, once when it loads, so
/// a program cannot change kernels once running. When betterBlasCoreType()
/// names a set and OPENBLAS_CORETYPE is not set already, this sets it and
/// re-executes the program (/proc/self/exe) with @a argv; if that fails it
/// returns and the program goes on with the slow kernels. Call it first
/// thing in main(), before any thread starts.
void useBestBlasKernels(char** argv);

} // namespace caps::fem
