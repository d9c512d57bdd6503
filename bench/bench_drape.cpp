// bench_drape: time to rest of the seed's RK4 against the static solver (cold
// and warm after a 10 % parameter change), on the seed's 30 x 30 set-up, a
// 100 x 100 grid disc and the cotton starter preset on a 100 x 100 grid (issue
// 13), at the same tolerance (relative force residual). Each case runs in its
// own child process so its peak memory is its own. The load average is printed
// beside every row (the machine is shared).
//
//   build/bin/bench_drape [--quick] [--static-only] [--rk4-wall-limit S] [--tolerance R]
//   build/bin/bench_drape --starters [--grids 41,61,81,101] [--plain] [--laying F] [--mesh grid|rings] [--preset FILE]...
//
// --starters: D, folds, wall time and Newton iterations of every
// starter fabric draped from flat (300 / 150 mm, seed 1, its own model options;
// --plain: without the crest-corrected bending stencils) at each grid, one
// drape at a time, with the spread of D and of the fold count over the grids;
// laid as `drape simulate` lays them (FabricPreset::laying: the starters at
// once; --laying F: first under F g, e.g. 0.4, the drape lab's); --mesh: the
// specimen's mesh (DrapeSetup::mesh, grid by default); --preset FILE: a preset
// file's row after the starters' (e.g. a fitted one; repeatable).
//
//   build/bin/bench_drape --late-shift [--grids 41,61] [--seeds K,K,...] [--preset FILE]...
//
// --late-shift (docs/decisions/0023-late-shift-from-flat.md): every preset (the starters without
// --preset) draped from flat as `drape simulate` drapes it, per grid and seed,
// with (the default) and without (late_shift_residual -1) the late shift (near
// rest, a failed exact factorisation shifts before it projects): D (folds), Newton iterations and wall
// time of both in one run (solver steps too: factorisations, the failed ones
// included, which RestOptions::max_newton counts), seeds 1 unless --seeds, each
// drape in its own child process, then the
// totals' ratios, the drapes whose fold count or D (by more than 0.05 point)
// differ, and the load average.
#include "engine/fabric/preset.hpp"
#include "engine/cloth/drape.hpp"
#include "engine/fabric/seed_format.hpp"
#include "engine/library/starter.hpp"

#include <cstdlib>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

using namespace drape::cloth;

namespace {

struct Row {
    std::string name;
    double wall = 0;
    long iters = 0, fevals = 0;
    long steps = 0; ///< static solver: factorisations, the failed ones included (what max_newton counts)
    double residual = 0, dc = 0;
    int nodes = 0;
    long vertices = 0;
    long peak_kb = 0;
    char status[32] = {0};
};

/// Runs `fn` in a child; the child writes its Row through a pipe.
template <class F>
Row in_child(F fn)
{
    int fd[2];
    if (pipe(fd) != 0) std::abort();
    const pid_t pid = fork();
    if (pid == 0) {
        close(fd[0]);
        Row r;
        try {
            r = fn();
        } catch (const std::exception& e) {
            std::fprintf(stderr, "bench_drape: %s\n", e.what());
            _exit(1); // the parent reads no row: "crashed"
        }
        if (write(fd[1], &r.wall, sizeof(double) * 1) < 0) _exit(1);
        const long ints[5] = {r.iters, r.fevals, r.nodes, r.vertices, r.steps};
        const double dbl[2] = {r.residual, r.dc};
        if (write(fd[1], ints, sizeof ints) < 0 || write(fd[1], dbl, sizeof dbl) < 0 || write(fd[1], r.status, sizeof r.status) < 0)
            _exit(1);
        _exit(0);
    }
    close(fd[1]);
    Row r;
    long ints[5] = {0, 0, 0, 0, 0};
    double dbl[2] = {0, 0};
    if (read(fd[0], &r.wall, sizeof(double)) <= 0 || read(fd[0], ints, sizeof ints) <= 0 || read(fd[0], dbl, sizeof dbl) <= 0 ||
        read(fd[0], r.status, sizeof r.status) <= 0)
        std::strcpy(r.status, "crashed");
    close(fd[0]);
    int wst = 0;
    struct rusage ru {};
    wait4(pid, &wst, 0, &ru);
    r.iters = ints[0];
    r.fevals = ints[1];
    r.nodes = static_cast<int>(ints[2]);
    r.vertices = ints[3];
    r.steps = ints[4];
    r.residual = dbl[0];
    r.dc = dbl[1];
    r.peak_kb = ru.ru_maxrss;
    return r;
}

Row to_row(const DrapeResult& d, long vertices)
{
    Row r;
    r.wall = d.status.wall_seconds;
    r.iters = d.status.integrator_steps();
    r.fevals = d.status.force_evaluations;
    r.steps = d.status.steps;
    r.residual = d.status.residual;
    r.dc = d.metrics.drape_coefficient_percent;
    r.nodes = d.metrics.node_count;
    r.vertices = vertices;
    std::snprintf(r.status, sizeof r.status, "%s", to_string(d.status.outcome).c_str());
    return r;
}

void print(const std::string& name, const Row& r)
{
    double load[1] = {0};
    if (getloadavg(load, 1) < 1) load[0] = -1;
    std::printf("| %-34s | %7ld | %9.2f | %9ld | %9ld | %8.1e | %5.1f | %2d | %8.1f | %-13s | %.2f |\n", name.c_str(), r.vertices, r.wall, r.iters,
                r.fevals, r.residual, r.dc, r.nodes, r.peak_kb / 1024.0, r.status, load[0]);
    std::fflush(stdout);
}

} // namespace

/// The starters under refinement: one row per starter, one column per grid.
int starters_table(const std::vector<int>& grids, bool plain, double laying, DrapeMesh mesh, const std::vector<std::string>& extra)
{
    std::printf("starters draped from flat, 300 / 150 mm, seed 1, %s mesh, %s%s; D [%%] (folds), wall [s], Newton iterations\n\n",
                to_string(mesh), laying > 0 ? ("laid under " + std::to_string(laying).substr(0, 4) + " g first").c_str() : "laid as each preset says",
                plain ? ", plain bending stencils (--plain)" : ", the presets' own model options");
    std::printf("| starter |");
    for (int g : grids) std::printf(" grid %d |", g);
    std::printf(" spread of D | folds | load avg |\n|---|");
    for (std::size_t i = 0; i < grids.size(); ++i) std::printf("---|");
    std::printf("---|---|---|\n");
    std::vector<std::pair<std::string, drape::fabric::FabricPreset>> rows;
    for (const auto& st : drape::library::starters()) rows.emplace_back(st.short_name, st.preset);
    for (const auto& f : extra) rows.emplace_back(f, drape::fabric::load_fabric(f));
    for (auto& [name, p] : rows) {
        if (plain) p.model.bending_correction = false;
        std::printf("| %s |", name.c_str());
        std::fflush(stdout);
        double lo = 1e9, hi = -1e9;
        int nlo = 1000, nhi = -1;
        for (int g : grids) {
            DrapeSetup setup;
            setup.sample_diameter = 0.30;
            setup.disc_diameter = 0.15;
            setup.grid = g;
            setup.mesh = mesh;
            setup = p.laid(setup); // `drape simulate`'s default
            if (laying > 0) setup.laying_load = laying;
            const Row r = in_child([&] { // `drape simulate`'s budget: 1,000 Newton iterations per level
                return to_row(simulate_drape(p.material(), setup, {}, p.model), 0);
            });
            std::printf(" %.2f (%d), %.1f s, %ld%s |", r.dc, r.nodes, r.wall, r.iters,
                        std::strcmp(r.status, "converged") ? (std::string(", ") + r.status).c_str() : "");
            std::fflush(stdout);
            if (!std::strcmp(r.status, "crashed")) continue;
            lo = std::min(lo, r.dc);
            hi = std::max(hi, r.dc);
            nlo = std::min(nlo, r.nodes);
            nhi = std::max(nhi, r.nodes);
        }
        double load[1] = {0};
        if (getloadavg(load, 1) < 1) load[0] = -1;
        std::printf(" %.2f | %d..%d | %.2f |\n", hi - lo, nlo, nhi, load[0]);
    }
    return 0;
}

/// `text` as a comma-separated list of integers in [lo, hi] into `out` (replaced);
/// false at the first item that is not one (--grids, --seeds).
static bool parse_ints(const char* text, long lo, long hi, std::vector<int>& out)
{
    out.clear();
    for (const char* c = text; *c;) {
        char* end = nullptr;
        const long v = std::strtol(c, &end, 10);
        if (end == c || v < lo || v > hi) return false;
        out.push_back(static_cast<int>(v));
        c = *end == ',' ? end + 1 : end;
    }
    return true;
}

/// The late shift's A/B: the same drapes from flat with and without it.
int late_shift_table(const std::vector<int>& grids, const std::vector<int>& seeds, const std::vector<std::string>& extra)
{
    std::vector<std::pair<std::string, drape::fabric::FabricPreset>> rows;
    if (extra.empty())
        for (const auto& st : drape::library::starters()) rows.emplace_back(st.short_name, st.preset);
    for (const auto& f : extra) rows.emplace_back(f, drape::fabric::load_fabric(f));
    std::printf("drapes from flat, 300 / 150 mm, each preset laid as `drape simulate` lays it; without -> with "
                "the late shift (RestOptions::late_shift_residual = kLateShiftResidual = %g)\n\n",
                kLateShiftResidual);
    std::printf("| preset | grid | seed | without: D [%%] (folds), Newton iterations (solver steps), wall [s] | with | iterations with / without | load avg |\n");
    std::printf("|---|---|---|---|---|---|---|\n");
    long it_off = 0, it_on = 0, st_off = 0, st_on = 0;
    double wall_off = 0, wall_on = 0;
    int n = 0, changed = 0, failed = 0;
    for (const auto& [name, p] : rows)
        for (int g : grids)
            for (int seed : seeds) {
                DrapeSetup setup;
                setup.sample_diameter = 0.30;
                setup.disc_diameter = 0.15;
                setup.grid = g;
                setup = p.laid(setup);
                setup.seed = static_cast<std::uint64_t>(seed);
                RestOptions off;
                off.late_shift_residual = -1;
                const Row a = in_child([&] { return to_row(simulate_drape(p.material(), setup, off, p.model), 0); });
                const Row b = in_child([&] { return to_row(simulate_drape(p.material(), setup, {}, p.model), 0); });
                double load[1] = {0};
                if (getloadavg(load, 1) < 1) load[0] = -1;
                const bool ok = !std::strcmp(a.status, "converged") && !std::strcmp(b.status, "converged");
                const bool differs = a.nodes != b.nodes || std::abs(a.dc - b.dc) > 0.05;
                std::printf("| %s | %d | %d | %.2f (%d), %ld (%ld), %.1f%s | %.2f (%d), %ld (%ld), %.1f%s | %.2f%s | %.2f |\n", name.c_str(), g, seed, a.dc,
                            a.nodes, a.iters, a.steps, a.wall, ok ? "" : (std::string(", ") + a.status).c_str(), b.dc, b.nodes, b.iters, b.steps, b.wall,
                            ok ? "" : (std::string(", ") + b.status).c_str(), a.iters > 0 ? double(b.iters) / a.iters : 0.0,
                            differs ? " (differs)" : "", load[0]);
                std::fflush(stdout);
                if (!ok) {
                    ++failed;
                    continue;
                }
                ++n;
                changed += differs ? 1 : 0;
                it_off += a.iters;
                it_on += b.iters;
                st_off += a.steps;
                st_on += b.steps;
                wall_off += a.wall;
                wall_on += b.wall;
            }
    double load[1] = {0};
    if (getloadavg(load, 1) < 1) load[0] = -1;
    std::printf("\n%d drapes at rest both ways (%d not): Newton iterations %ld -> %ld (ratio %.3f), solver steps %ld -> %ld (ratio %.3f), "
                "wall %.1f -> %.1f s (ratio %.3f); %d with another fold count or a D more than 0.05 point off; load average %.2f\n",
                n, failed, it_off, it_on, it_off ? double(it_on) / it_off : 0.0, st_off, st_on, st_off ? double(st_on) / st_off : 0.0, wall_off,
                wall_on, wall_off > 0 ? wall_on / wall_off : 0.0, changed, load[0]);
    return 0;
}

/// The command line.
struct BenchArgs {
    double rk4_limit = 900, tol = 1e-6;
    bool quick = false, static_only = false, starters = false, plain = false, starters_option = false, late_shift = false;
    std::vector<int> seeds = {1};
    bool seeds_given = false, grids_given = false;
    double laying = 0; // 0: each preset's own (FabricPreset::laying: a starter at once)
    std::vector<int> grids = {41, 61, 81, 101};
    DrapeMesh mesh = DrapeMesh::Grid;
    std::vector<std::string> extra;
};

/// Reads the command line into `a`; 0, or 2 after a usage message.
int parse_args(int argc, char** argv, BenchArgs& a)
{
    for (int i = 1; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--starters")) a.starters = true;
        else if (!std::strcmp(argv[i], "--late-shift")) a.late_shift = true;
        else if (!std::strcmp(argv[i], "--seeds") && i + 1 < argc) {
            a.seeds_given = true;
            if (!parse_ints(argv[++i], 0, 1000000, a.seeds)) {
                std::fprintf(stderr, "bench_drape: --seeds: '%s' is not a list of seeds in [0, 1000000]\n", argv[i]);
                return 2;
            }
        }
        else if (!std::strcmp(argv[i], "--plain")) a.plain = true;
        else if (!std::strcmp(argv[i], "--laying") && i + 1 < argc) {
            a.starters_option = true;
            a.laying = std::atof(argv[++i]);
            if (!(a.laying > 0 && a.laying <= 1)) {
                std::fprintf(stderr, "bench_drape: --laying: '%s' is not a fraction of gravity in (0, 1]\n", argv[i]);
                return 2;
            }
        }
        else if (!std::strcmp(argv[i], "--mesh") && i + 1 < argc) {
            a.starters_option = true;
            try {
                a.mesh = drape_mesh_from_string(argv[++i]);
            } catch (const std::exception& e) {
                std::fprintf(stderr, "bench_drape: --%s\n", e.what());
                return 2;
            }
        } else if (!std::strcmp(argv[i], "--preset") && i + 1 < argc) {
            a.starters_option = true;
            a.extra.emplace_back(argv[++i]);
        }
        else if (!std::strcmp(argv[i], "--grids") && i + 1 < argc) {
            a.starters_option = true;
            a.grids_given = true;
            if (!parse_ints(argv[++i], 5, 401, a.grids)) {
                std::fprintf(stderr, "bench_drape: --grids: '%s' is not a list of grids in [5, 401]\n", argv[i]);
                return 2;
            }
        } else if (!std::strcmp(argv[i], "--quick")) a.quick = true;
        else if (!std::strcmp(argv[i], "--static-only")) a.static_only = true;
        else if (!std::strcmp(argv[i], "--rk4-wall-limit") && i + 1 < argc) a.rk4_limit = std::atof(argv[++i]);
        else if (!std::strcmp(argv[i], "--tolerance") && i + 1 < argc) a.tol = std::atof(argv[++i]);
        else {
            std::fprintf(stderr, "usage: bench_drape [--quick] [--static-only] [--rk4-wall-limit S] [--tolerance R]\n"
                                 "       bench_drape --starters [--grids 41,61,81,101] [--plain] [--laying F] [--mesh grid|rings] [--preset FILE]...\n"
                                 "       bench_drape --late-shift [--grids 41,61] [--seeds K,K,...] [--preset FILE]...\n");
            return 2;
        }
    }
    return 0;
}

/// The solver table: the seed's set-up, the cotton starter and a mid-weight fabric
/// at grid 100, static cold and warm, and RK4.
int solver_table(const BenchArgs& a)
{
    const double rk4_limit = a.rk4_limit, tol = a.tol;
    const bool quick = a.quick, static_only = a.static_only;
    std::printf("tolerance: relative force residual %.0e; RK4 stops at %.0f s wall if not at rest\n\n", tol, rk4_limit);
    std::printf("| case                               | vertices | wall [s] | iters/steps | force evals | residual | D [%%] | nodes | peak [MB] | status | load avg |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|---|\n");

    // Dampers do not change a rest state; the seed's dashpots (7 N*s/m on a 0.02 g
    // particle) would force RK4 to 3e-7 s steps, so RK4 runs the same springs with
    // light dashpots plus air damping (as tests/cloth/tst_drape_slow does).
    auto rk4_case = [&](const Material& fabric, DrapeSetup setup) {
        return in_child([=] {
            auto sys = make_drape_system(fabric, setup);
            sys->model().air_damping = 8.0;
            RestOptions ro;
            ro.integrator = Integrator::RK4;
            ro.residual = tol;
            ro.max_speed = 1e-5;
            ro.max_sim_time = 1e9;
            const auto t0 = std::chrono::steady_clock::now();
            ro.progress = [=](const SolverStatus&) {
                return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() < rk4_limit;
            };
            const SolverStatus st = run_to_rest(*sys, ro);
            DrapeResult d = measure_drape(*sys, setup);
            d.status = st;
            Row r = to_row(d, sys->vertex_count());
            if (st.outcome == SolverStatus::Outcome::Cancelled) std::snprintf(r.status, sizeof r.status, "stopped at limit");
            return r;
        });
    };
    auto static_cases = [&](const Material& fabric, const Material& changed, DrapeSetup setup, Row& cold, Row& warm) {
        RestOptions ro;
        ro.integrator = Integrator::Static;
        ro.residual = tol;
        cold = in_child([=] { return to_row(simulate_drape(fabric, setup, ro), 0); });
        warm = in_child([=] {
            const DrapeResult base = simulate_drape(fabric, setup, ro);
            const DrapeResult w = simulate_drape_from(changed, setup, base.x, ro);
            return to_row(w, base.x.rows());
        });
        cold.vertices = warm.vertices;
    };

    // 1. The seed's set-up: Table 1 on its 30 x 30 grid.
    {
        DrapeSetup setup;
        using drape::fabric::SeedParams;
        auto material = [](const SeedParams& s) {
            return Material(drape::fabric::continuum_from_seed(s), drape::fabric::grid_springs(s));
        };
        SeedParams light = SeedParams::table1();
        light.sst_du = light.sst_dv = light.ssh_d = light.sfl_du = light.sfl_dv = 2e-3;
        SeedParams changed = SeedParams::table1();
        changed.sfl_ku *= 1.1;
        changed.sfl_kv *= 1.1;
        Row cold, warm;
        static_cases(material(SeedParams::table1()), material(changed), setup, cold, warm);
        print("seed 30x30, static, cold", cold);
        print("seed 30x30, static, warm (+10 % flexion)", warm);
        if (!static_only) {
            const Row rk = rk4_case(material(light), setup);
            print("seed 30x30, RK4 (seed's integrator)", rk);
            std::printf("|  ratio RK4 / static: cold %.1fx, warm %.1fx (wall time) |\n", rk.wall / cold.wall, rk.wall / warm.wall);
        }
        std::printf("\n");
    }
    if (quick) return 0;
    // 2. The cotton starter's parameters (data/library/cotton-plain-weave.json) with the plain stencils
    // on a 300 mm specimen over a 150 mm disc, grid 100.
    {
        DrapeSetup setup;
        setup.grid = 100;
        const FabricParams p = drape::library::find_starter("cotton")->params;
        FabricParams q = p;
        q[Param::BendWarp] *= 1.1;
        q[Param::BendWeft] *= 1.1;
        Row cold, warm;
        static_cases(p, q, setup, cold, warm);
        print("cotton 100x100, plain stencils, cold", cold);
        print("cotton 100x100, plain stencils, warm (+10 %)", warm);
        std::printf("\n");
    }
    // 3. A 100 x 100 grid disc (about 7,700 particles) of a mid-weight fabric.
    {
        DrapeSetup setup;
        setup.grid = 100;
        FabricParams p;
        p[Param::BendWarp] = 5e-5;
        p[Param::BendWeft] = 4e-5;
        FabricParams q = p;
        q[Param::BendWarp] *= 1.1;
        q[Param::BendWeft] *= 1.1;
        Row cold, warm;
        static_cases(p, q, setup, cold, warm);
        print("100x100 disc, static, cold", cold);
        print("100x100 disc, static, warm (+10 % bending)", warm);
        if (static_only) return 0;
        const Row rk = rk4_case(p, setup);
        print("100x100 disc, RK4", rk);
        std::printf("|  ratio RK4 / static: cold %.1fx, warm %.1fx (wall time%s) |\n", rk.wall / cold.wall, rk.wall / warm.wall,
                    std::strcmp(rk.status, "converged") ? "; RK4 not at rest: a lower bound" : "");
    }
    return 0;
}

int main(int argc, char** argv)
{
    BenchArgs a;
    if (const int rc = parse_args(argc, argv, a)) return rc;
    const bool late_shift = a.late_shift, starters = a.starters, plain = a.plain, starters_option = a.starters_option, seeds_given = a.seeds_given;
    const bool quick = a.quick, static_only = a.static_only;
    const double rk4_limit = a.rk4_limit, tol = a.tol, laying = a.laying;
    const DrapeMesh mesh = a.mesh;
    std::vector<int> grids = a.grids;
    const std::vector<int>& seeds = a.seeds;
    const std::vector<std::string>& extra = a.extra;
    if (late_shift) {
        if (!a.grids_given) grids = {41, 61};
        if (grids.empty() || seeds.empty()) {
            std::fprintf(stderr, "bench_drape: --%s: no %s\n", grids.empty() ? "grids" : "seeds", grids.empty() ? "grid" : "seed");
            return 2;
        }
        if (starters || plain || laying > 0 || mesh != DrapeMesh::Grid || quick || static_only || rk4_limit != 900 || tol != 1e-6) {
            std::fprintf(stderr, "bench_drape: --late-shift goes with --grids, --seeds and --preset only\n");
            return 2;
        }
        try {
            return late_shift_table(grids, seeds, extra);
        } catch (const std::exception& e) {
            std::fprintf(stderr, "bench_drape: %s\n", e.what());
            return 1;
        }
    }
    if (seeds_given) {
        std::fprintf(stderr, "bench_drape: --seeds goes with --late-shift\n");
        return 2;
    }
    if (starters) {
        if (grids.empty()) {
            std::fprintf(stderr, "bench_drape: --grids: no grid\n");
            return 2;
        }
        try {
            return starters_table(grids, plain, laying, mesh, extra);
        } catch (const std::exception& e) {
            std::fprintf(stderr, "bench_drape: %s\n", e.what());
            return 1;
        }
    }
    if (plain || starters_option) {
        std::fprintf(stderr, "bench_drape: --grids, --plain, --laying, --mesh and --preset go with --starters\n");
        return 2;
    }
    return solver_table(a);
}
