#include "engine/cloth/sparse_cholesky.hpp"

#include "engine/cloth/blas_threads.hpp"

#include <algorithm>
#include <cstdlib>
#include <mutex>
#include <string>
#include <vector>

// OpenMP's runtime, when CHOLMOD brought it into the process (weak: null otherwise).
extern "C" void omp_set_max_active_levels(int) __attribute__((weak));

namespace drape::cloth::detail {

namespace {

/// CHOLMOD settings for the cloth Hessians, before analyzePattern.
///
/// Threads: Debian's CHOLMOD 3.0 (SuiteSparse 5.12) runs the copy loops of its
/// supernodal factorisation in OpenMP regions with a compiled-in
/// num_threads(4) (CHOLMOD_OMP_NUM_THREADS), whatever OMP_NUM_THREADS says.
/// On this 2-core machine that made every factorisation wait on futexes: 167 ms
/// instead of 59 ms at 23,004 unknowns (41 s of system time in a 113 s drape).
/// The numerical work is BLAS, set to one thread at the first factorisation
/// (single_threaded_blas: the same rounding in every drape); the regions are
/// made inactive (the project has no other OpenMP code) unless the user chose
/// through OMP_MAX_ACTIVE_LEVELS or OMP_THREAD_LIMIT - on every thread that
/// factorises: OpenMP 5 made max-active-levels an ICV of each thread's data
/// environment (libgomp keeps it per thread since GCC 11), so the setting made
/// once, on the first thread, left a fit's worker threads opening CHOLMOD's
/// regions with four threads each: a fit's two drapes at once took 24 ms per
/// Newton iteration each instead of 12 (A03's preset from flat, seeds 1001 and
/// 1003 on two threads: 9.3 s -> 5.4 s, the same iterations and rest states).
///
/// Ordering: METIS nested dissection instead of CHOLMOD's default AMD (METIS is
/// tried by default only when AMD's fill looks poor, and it did not here): on the
/// 100 x 100 disc 1.0 Gflop and 3.7 M factor entries instead of 1.7 Gflop and
/// 4.4 M, factorisation 43 ms instead of 59 ms; the analysis (once per mesh) costs
/// 50 ms instead of 15 ms.
void configure_cholmod(Cholmod& llt)
{
    thread_local bool omp_configured = false;
    if (!omp_configured) {
        omp_configured = true;
        if (omp_set_max_active_levels && !std::getenv("OMP_MAX_ACTIVE_LEVELS") && !std::getenv("OMP_THREAD_LIMIT"))
            omp_set_max_active_levels(0);
    }
    static std::once_flag once;
    std::call_once(once, [] {
        // The first factorisation rounds as every later one: OpenBLAS's default
        // thread count follows the machine, and a drape made before a command
        // or a fit called single_threaded_blas() (a test's synthetic record)
        // rounded otherwise - a fold-dependent fit then drifted between runs
        // (ratio 0.83 vs 0.84 on one record). tst_drape checks it.
        single_threaded_blas();
    });
    auto& c = llt.cholmod();
    c.print = 0; // numerical outcomes are reported through the status, not stderr
    llt.setMode(Eigen::CholmodSupernodalLLt);
    const char* ord = std::getenv("DRAPE_CHOLMOD_ORDERING");
    if (!(ord && std::string(ord) == "default")) {
        c.nmethods = 1;
        c.method[0].ordering = CHOLMOD_METIS;
        c.postorder = 1;
    }
}


/// The last symbolic analysis made on this thread, kept for the next static
/// solve of the same sparsity pattern: a warm re-solve (a fit's next
/// evaluation, simulate_drape_from) builds a new system on the same mesh, and
/// METIS costs 50 ms at 23k unknowns, about one Newton iteration. The factor's
/// memory (30 MB at 23k unknowns) stays with the thread until a solve of
/// another pattern replaces it. A solve takes the object out while it runs.
struct AnalysedPattern {
    std::vector<int> outer, inner;
    std::unique_ptr<Cholmod> llt;
    bool matches(const SpMat& A) const
    {
        return llt && outer.size() == static_cast<std::size_t>(A.outerSize() + 1) && inner.size() == static_cast<std::size_t>(A.nonZeros()) &&
               std::equal(outer.begin(), outer.end(), A.outerIndexPtr()) && std::equal(inner.begin(), inner.end(), A.innerIndexPtr());
    }
};
thread_local AnalysedPattern t_last_analysis;

/// One symbolic analysis at a time in the process. METIS (Debian's libmetis
/// 5.1.0) draws its random numbers from the C library's rand(), reseeded with
/// srand(4321) at the start of every ordering: one stream for the whole
/// process. Two analyses at once (a fit's seeds on two threads) interleave their
/// draws and get other orderings than a lone analysis, hence other rounding in
/// every factorisation: the drapes, and a fit's chi2, depended on timing (chi2
/// 44.8 / 46.8 for the same grid-41 fit). The wait is at most one analysis
/// (2 ms at grid 25, 6 ms at grid 41), once per mesh and thread.
std::mutex g_analysis_mutex;

} // namespace

std::unique_ptr<Cholmod> take_analysed(const SpMat& A, bool& reused)
{
    AnalysedPattern& last = t_last_analysis;
    reused = last.matches(A);
    if (reused) return std::move(last.llt);
    last.llt.reset(); // free the old factor before the new analysis
    auto llt = std::make_unique<Cholmod>();
    configure_cholmod(*llt);
    {
        std::lock_guard lock(g_analysis_mutex);
        llt->analyzePattern(A);
    }
    return llt;
}

void keep_analysed(std::unique_ptr<Cholmod> llt, const SpMat& A)
{
    if (!llt) return;
    AnalysedPattern& last = t_last_analysis;
    last.outer.assign(A.outerIndexPtr(), A.outerIndexPtr() + A.outerSize() + 1);
    last.inner.assign(A.innerIndexPtr(), A.innerIndexPtr() + A.nonZeros());
    last.llt = std::move(llt);
}


bool uses_metis(Cholmod& llt) { return llt.cholmod().method[llt.cholmod().selected].ordering == CHOLMOD_METIS; }

} // namespace drape::cloth::detail
