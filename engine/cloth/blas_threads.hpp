#pragma once
// The sparse solver's BLAS (OpenBLAS when it is the one in use) and threads.

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
void single_threaded_blas();

} // namespace drape::cloth
