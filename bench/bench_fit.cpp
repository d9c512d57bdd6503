// bench_fit: full fits of drape-test records, the sensitivity fit (Levenberg-
// Marquardt on the exact rest-state sensitivities, `drape fit`'s default) and
// the derivative-free NLopt fit before it, in the same run.
// Per record and method: wall time, drapes, Hessian factorisations and
// back-substitutions of the sensitivities, evaluations, chi2, the D and node
// errors as fitted and of the preset draped from flat (random start, as `drape
// predict`). Prints the load average before and after: on the 2-core machine
// other work slows every row alike.
//
//   build/bin/bench_fit [RECORD_DIR ...] [--grid N] [--methods lm,nlopt]
//                       [--set KEY=VALUE] [--branch measured|random] [--cores 1|2] [--plain] [--trace]
// RECORD_DIR defaults to examples/DL-A04 (a copy of a set-a record). The
// defaults are `drape fit`'s: grid 41, measured branch, corrected bending stencils (--plain: the plain ones), buckling_length_m of
// the fit's start (see engine/estimate/fit.hpp FitOptions).
#include "engine/cloth/params.hpp"
#include "engine/estimate/fit.hpp"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

using namespace drape;

namespace {
std::string loadavg()
{
    std::ifstream f("/proc/loadavg");
    std::string a, b, c;
    f >> a >> b >> c;
    return a + " " + b + " " + c;
}
} // namespace

int main(int argc, char** argv)
{
    std::vector<std::string> dirs;
    int grid = 41, cores = 2;
    bool trace = false;
    std::vector<estimate::FitMethod> methods{estimate::FitMethod::Sensitivity, estimate::FitMethod::Nlopt};
    estimate::FitOptions base = estimate::drape_fit_defaults(); // --plain: the plain stencils
    cloth::FabricParams start = *base.start;
    try {
        for (int i = 1; i < argc; ++i) {
            const std::string a = argv[i];
            const bool more = i + 1 < argc;
            if (a == "--grid" && more) grid = std::atoi(argv[++i]);
            else if (a == "--cores" && more) cores = std::atoi(argv[++i]);
            else if (a == "--trace") trace = true;
            else if (a == "--plain") base.model_options.bending_correction = false;
            else if (a == "--branch" && more) base.branch = estimate::parse_fold_branch(argv[++i]);
            else if (a == "--methods" && more) {
                methods.clear();
                std::stringstream ss(argv[++i]);
                for (std::string m; std::getline(ss, m, ',');) methods.push_back(estimate::parse_fit_method(m));
            } else if (a == "--set" && more) {
                const std::string kv = argv[++i];
                const auto eq = kv.find('=');
                const cloth::ParamSpec* sp = eq == std::string::npos ? nullptr : cloth::find_param(kv.substr(0, eq));
                if (!sp) throw std::runtime_error("--set " + kv + ": not KEY=VALUE with a key of the parameter table");
                start[sp->id] = std::atof(kv.c_str() + eq + 1);
            } else if (a[0] != '-') dirs.push_back(a);
            else {
                std::fprintf(stderr, "usage: bench_fit [RECORD_DIR ...] [--grid N] [--methods lm,nlopt] [--set KEY=VALUE] "
                                     "[--branch measured|random] [--cores 1|2] [--plain] [--trace]\n");
                return 2;
            }
        }
        if (dirs.empty()) dirs.push_back(DRAPE_SOURCE_DIR "/examples/DL-A04");
        std::printf("bench_fit: grid %d, model baseline, %s bending stencils, branch %s, buckling_length_m %.4g, %d core(s), default "
                    "budgets, seed 1; as `drape fit`: laid under %.2g g, %.3g mm waviness from flat, the preset also from flat at grid %d, "
                    "calibration from flat %s\n",
                    grid, base.model_options.bending_correction ? "corrected" : "plain", estimate::to_string(base.branch).c_str(),
                    start[cloth::Param::BucklingLength], cores, base.laying_load, base.perturbation_m * 1e3, base.flat_check_grid,
                    base.flat_calibration ? "on" : "off");
        std::printf("load average before: %s\n\n", loadavg().c_str());
        std::printf("| record | method | wall [s] | drapes | factorisations | back-substitutions | evaluations | chi2 / dof | "
                    "D err fitted | nodes err fitted | D err from flat | nodes err from flat | warp / weft bending | 60 s |\n");
        std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
        std::fflush(stdout);
        for (const auto& dir : dirs) {
            const estimate::MeasuredDrape rec = estimate::load_record(dir);
            for (auto m : methods) {
                estimate::FitOptions o = base;
                o.grid = grid;
                o.method = m;
                o.parallel_seeds = cores;
                o.start = start;
                if (trace) { // one line per evaluation: where the time goes
                    auto last = std::make_shared<double>(0.0);
                    o.progress = [last](const estimate::FitProgress& p) {
                        std::fprintf(stderr, "  %-11s eval %3d  sims %4ld  %+7.2f s  t %7.1f s  best chi2 %.4g\n", p.stage.c_str(), p.evaluation,
                                     p.simulations, p.elapsed_s - *last, p.elapsed_s, p.best_chi2);
                        *last = p.elapsed_s;
                    };
                }
                const auto t0 = std::chrono::steady_clock::now();
                const estimate::FitResult r = estimate::fit_fabric({rec}, o);
                const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
                const auto& rf = r.records.front();
                std::printf("| %s | %s | %.1f | %ld | %ld | %ld | %d | %.1f / %d | %+.1f | %+.1f | %+.1f | %+.1f | %.2g / %.2g | %s |\n",
                            rec.id.c_str(), estimate::to_string(m).c_str(), wall, r.simulations, r.factorisations, r.back_substitutions,
                            r.evaluations, r.chi2, r.dof, rf.dc_error_percent, rf.node_error, rf.cold_dc_error_percent, rf.cold_node_error,
                            r.params[cloth::Param::BendWarp], r.params[cloth::Param::BendWeft], wall <= 60 ? "met" : "not met");
                std::fflush(stdout);
            }
        }
        std::printf("\nload average after: %s\n", loadavg().c_str());
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_fit: %s\n", e.what());
        return 1;
    }
    return 0;
}
