// threads PRESET [p]: two drapes from flat (grid 41, 300/150 mm, laid at 0.4 g,
// seeds 1001 and 1003) one after the other on the main thread, or with `p` on two
// std::threads at once, as a fit's parallel_for runs them. Prints wall time and
// milliseconds per Newton iteration of each. Found the OpenMP regions CHOLMOD
// opened on worker threads (docs/performance.md, fourteenth session): before the
// fix 24 ms per iteration on two threads against 12-15 ms alone. Build with
// -fopenmp added to the probe line of README.md (the program itself calls no
// OpenMP; with FIXOMP set it switches the regions off on each thread by hand).
#include "engine/cloth/blas_threads.hpp"
#include "engine/cloth/drape.hpp"
#include "engine/fabric/preset.hpp"

#include <omp.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <thread>

using namespace drape;

int main(int argc, char** argv)
{
    if (argc < 2) {
        std::fprintf(stderr, "usage: threads PRESET [p]\n");
        return 2;
    }
    const auto preset = fabric::load_fabric(argv[1]);
    cloth::single_threaded_blas();
    auto run = [&](std::uint64_t seed) {
        if (std::getenv("FIXOMP")) omp_set_max_active_levels(0);
        cloth::DrapeSetup s;
        s.sample_diameter = 0.3;
        s.disc_diameter = 0.15;
        s.grid = 41;
        s.seed = seed;
        s.laying_load = 0.4;
        const auto t0 = std::chrono::steady_clock::now();
        const auto r = cloth::simulate_drape(preset.material(), s);
        const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::printf("seed %lu: %.2f s, %ld steps, %.2f ms per step, D %.2f %%\n", static_cast<unsigned long>(seed), t, r.status.steps,
                    1e3 * t / static_cast<double>(r.status.steps), r.metrics.drape_coefficient_percent);
    };
    const auto t0 = std::chrono::steady_clock::now();
    if (argc < 3) {
        run(1001);
        run(1003);
    } else {
        std::thread a([&] { run(1001); }), b([&] { run(1003); });
        a.join();
        b.join();
    }
    std::printf("%s %.2f s\n", argc < 3 ? "one after the other" : "on two threads",
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
}
