#pragma once
// The sparse solver's BLAS (OpenBLAS when it is the one in use): its threads and
// the kernels it rounds with.
#include <string>

namespace drape::cloth {

/// Limits OpenBLAS (used by CHOLMOD's supernodal factorisation) to one thread.
/// OpenBLAS's own threads fight parallel simulations (and other processes) on
/// small machines: measured 36 s wall with 35 s of system time for 8 drapes at
/// grid 25, 16 s with one BLAS thread. Looked up at run time, so a reference
/// BLAS works too. Call it before running several simulations in parallel.
/// The commands and the widget all call it before a solve, and the first sparse
/// factorisation of a process calls it too, so the factorisation rounds the same
/// way in each: a buckling drape (a skirt's settling fall) can take another fold
/// branch when the rounding differs.
///
/// The first call also pins OpenBLAS's kernels to kPortableBlasKernel
/// (portable_blas_kernel), so that every machine rounds alike.
void single_threaded_blas();

/// The OpenBLAS kernels every machine with AVX2 and FMA can run (x86-64 since
/// 2013-2015), and the ones Debian's OpenBLAS picks itself on AVX2 machines
/// (Haswell, and Zen, whose kernels are Haswell's).
inline constexpr const char* kPortableBlasKernel = "Haswell";

/// Makes Debian's OpenBLAS (built for every x86-64 core, choosing at load)
/// use kPortableBlasKernel instead of the machine's own, once per process, so
/// that the same build of the project and of Debian's OpenBLAS, CHOLMOD and
/// METIS rounds alike on every AVX2 + FMA machine:
/// the supernodal factorisation's blocks are summed in the kernels' order, and
/// a drape from flat chooses its fold branch on that rounding. Measured: the
/// same fits of the lab's DL-A02 and DL-A05 with the AVX-512 kernels
/// (Cooperlake, SkylakeX) and the AVX2 ones (Haswell, Zen) on one machine - chi2
/// 42.56 / 43.06 and 104.6 / 120.0, DL-A05's warp/weft bending 0.14 separated /
/// 0.19 tied and its preset from flat 5 / 7 folds - while each pair agreed to
/// the digit, and the AVX2 kernels' numbers were another machine's to the digit
/// (docs/decisions/0027-portable-blas-kernels.md). The speed is the same (a
/// grid-101 drape 32.1 s against 31.0 s with the AVX-512 kernels).
/// Left alone: a user's OPENBLAS_CORETYPE (OpenBLAS read it at load),
/// DRAPE_NATIVE_BLAS=1, a machine without AVX2 and FMA (the kernels would not
/// run), and a BLAS that is not a dynamic-architecture OpenBLAS or lacks those
/// kernels. It sets and clears OPENBLAS_CORETYPE in the environment, which is
/// not safe while other threads read it: the first call belongs at start-up,
/// before threads - the commands' and the demo's main() make it, the widget's
/// controller on the GUI thread; a host process that embeds the engine should
/// call it first too (single_threaded_blas and the first factorisation call it
/// as a fallback). Returns blas_kernel().
std::string portable_blas_kernel();

/// The kernels in use: OpenBLAS's core name ("Haswell", "Cooperlake", ...),
/// "not OpenBLAS" for another BLAS. Written into a fit's provenance.
std::string blas_kernel();

} // namespace drape::cloth
