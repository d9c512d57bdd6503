// bench_fit: one full fit of one record at the default resolution (issue 4's
// benchmark: target under 60 s on one core). Prints the wall time, the
// simulations per fit and the time per simulation, for one core (simulations
// one after another) and, with --both, for two (the CLI default, two seeds in
// parallel).
//
//   build/bin/bench_fit [RECORD_DIR] [--grid N] [--both] [--trace]
// --trace prints one line per evaluation (stage, time) on stderr.
// RECORD_DIR defaults to examples/DL-A04 (a copy of a set-a record).
#include "engine/estimate/fit.hpp"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

using namespace drape;

int main(int argc, char** argv)
{
    std::string dir = DRAPE_SOURCE_DIR "/examples/DL-A04";
    int grid = 25;
    bool both = false, trace = false;
    for (int i = 1; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--grid") && i + 1 < argc) grid = std::atoi(argv[++i]);
        else if (!std::strcmp(argv[i], "--both")) both = true;
        else if (!std::strcmp(argv[i], "--trace")) trace = true;
        else if (argv[i][0] != '-') dir = argv[i];
        else {
            std::fprintf(stderr, "usage: bench_fit [RECORD_DIR] [--grid N] [--both] [--trace]\n");
            return 2;
        }
    }
    try {
        const estimate::MeasuredDrape rec = estimate::load_record(dir);
        std::printf("bench_fit: %s, grid %d, model baseline, default budgets, seed 1\n\n", rec.id.c_str(), grid);
        std::printf("| cores | wall [s] | simulations | s per simulation | evaluations | D err | nodes err | target 60 s |\n");
        std::printf("|---|---|---|---|---|---|---|---|\n");
        const std::vector<int> cores = both ? std::vector<int>{1, 2} : std::vector<int>{1};
        for (int threads : cores) {
            estimate::FitOptions o;
            o.grid = grid;
            o.parallel_seeds = threads;
            if (trace) { // one line per evaluation: where the time goes
                auto last = std::make_shared<double>(0.0);
                o.progress = [last](const estimate::FitProgress& p) {
                    char at[256] = "";
                    std::size_t used = 0;
                    for (double c : p.last_coords)
                        if (used < sizeof at) used += static_cast<std::size_t>(std::snprintf(at + used, sizeof at - used, " %.3f", c));
                    std::fprintf(stderr, "  %-11s eval %3d  sims %4ld (%ld not at rest)  %+7.2f s  t %7.1f s  best chi2 %.4g  at%s\n", p.stage.c_str(),
                                 p.evaluation, p.simulations, p.unconverged, p.elapsed_s - *last, p.elapsed_s, p.best_chi2, at);
                    *last = p.elapsed_s;
                };
            }
            const auto t0 = std::chrono::steady_clock::now();
            const estimate::FitResult r = estimate::fit_fabric({rec}, o);
            const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            std::printf("| %d | %.1f | %ld | %.2f | %d | %+.1f | %+.1f | %s |\n", threads, wall, r.simulations, wall / std::max(1L, r.simulations),
                        r.evaluations, r.records[0].dc_error_percent, r.records[0].node_error, wall < 60 ? "met" : "not met");
            std::fflush(stdout);
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_fit: %s\n", e.what());
        return 1;
    }
    return 0;
}
