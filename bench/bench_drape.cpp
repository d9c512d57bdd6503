// bench_drape: time to rest of the seed's RK4 against the static solver (cold
// and warm after a 10 % parameter change), on the seed's 30 x 30 set-up, a
// 100 x 100 grid disc and the cotton starter preset on a 100 x 100 grid (issue
// 13), at the same tolerance (relative force residual). Each case runs in its
// own child process so its peak memory is its own. The load average is printed
// beside every row (the machine is shared).
//
//   build/bin/bench_drape [--quick] [--static-only] [--rk4-wall-limit S] [--tolerance R]
#include "engine/cloth/drape.hpp"
#include "engine/fabric/seed_format.hpp"
#include "engine/library/starter.hpp"

#include <cstdlib>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
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
        Row r = fn();
        if (write(fd[1], &r.wall, sizeof(double) * 1) < 0) _exit(1);
        const long ints[4] = {r.iters, r.fevals, r.nodes, r.vertices};
        const double dbl[2] = {r.residual, r.dc};
        if (write(fd[1], ints, sizeof ints) < 0 || write(fd[1], dbl, sizeof dbl) < 0 || write(fd[1], r.status, sizeof r.status) < 0)
            _exit(1);
        _exit(0);
    }
    close(fd[1]);
    Row r;
    long ints[4];
    double dbl[2];
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

int main(int argc, char** argv)
{
    double rk4_limit = 900, tol = 1e-6;
    bool quick = false, static_only = false;
    for (int i = 1; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--quick")) quick = true;
        else if (!std::strcmp(argv[i], "--static-only")) static_only = true;
        else if (!std::strcmp(argv[i], "--rk4-wall-limit") && i + 1 < argc) rk4_limit = std::atof(argv[++i]);
        else if (!std::strcmp(argv[i], "--tolerance") && i + 1 < argc) tol = std::atof(argv[++i]);
        else {
            std::fprintf(stderr, "usage: bench_drape [--quick] [--static-only] [--rk4-wall-limit S] [--tolerance R]\n");
            return 2;
        }
    }
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
    // 2. Issue 13's case: the cotton starter preset (data/library/cotton-plain-weave.json)
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
        print("cotton 100x100, static, cold", cold);
        print("cotton 100x100, static, warm (+10 % bending)", warm);
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
