// bench_garment: the circle skirt on the default mannequin (Debian's MakeHuman
// body) for several fabrics, the way `drape garment` drapes it: time to rest,
// Newton iterations (the settling fall's linear solves included), and what a
// person compares (hem radius, folds, self-intersections, vertices inside the
// body). Prints the ratio of the widest to the narrowest hem, the load average,
// and accepts the settling parameters so their effect can be measured.
//
//   build/bin/bench_garment [--fabrics silk,denim] [--dt S] [--duration S] [--damping 1/S]
//                           [--iterations N] [--body FILE] [--segments N] [--max-newton N] [--trace]
//                           [--self-collision on,off]
//
// --self-collision on,off drapes every fabric both ways in the same run and
// prints the ratio of wall times (on / off): the cost of the self-contact.
#include "engine/cloth/blas_threads.hpp"
#include "engine/library/starter.hpp"
#include "importers/garment_metrics.hpp"
#include "importers/garment_scene.hpp"

#include <algorithm>
#include <sys/resource.h>
#include <chrono>
#include <stdexcept>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

using namespace drape;

namespace {

long peak_mb()
{
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return u.ru_maxrss / 1024;
}

double load_average()
{
    double l[3] = {0, 0, 0};
    return getloadavg(l, 3) > 0 ? l[0] : -1;
}

} // namespace

int main(int argc, char** argv)
{
    try {
        std::vector<std::string> fabrics = {"silk", "denim"};
        importers::Settling settle;
        std::string body = importers::default_mannequin_path();
        importers::SkirtOptions so;
        bool trace = false;
        long max_newton = 0;
        std::vector<std::string> self_modes = {"on"};
        for (int i = 1; i < argc; ++i) {
            const std::string k = argv[i];
            auto next = [&]() -> std::string {
                if (i + 1 >= argc) throw std::runtime_error(k + " needs a value");
                return argv[++i];
            };
            if (k == "--fabrics") {
                fabrics.clear();
                std::stringstream ss(next());
                for (std::string f; std::getline(ss, f, ',');) fabrics.push_back(f);
            } else if (k == "--dt") settle.dt = std::stod(next());
            else if (k == "--duration") settle.duration = std::stod(next());
            else if (k == "--damping") settle.damping_rate = std::stod(next());
            else if (k == "--iterations") settle.iterations = std::stoi(next());
            else if (k == "--body") body = next();
            else if (k == "--segments") so.segments = std::stoi(next());
            else if (k == "--trace") trace = true;
            else if (k == "--max-newton") max_newton = std::stol(next());
            else if (k == "--self-collision") {
                self_modes.clear();
                std::stringstream ss(next());
                for (std::string f; std::getline(ss, f, ',');) {
                    if (f != "on" && f != "off") throw std::runtime_error("--self-collision: " + f + " is not on or off");
                    self_modes.push_back(f);
                }
            }
            else throw std::runtime_error("unknown flag " + k);
        }
        std::printf("circle skirt on %s; settling dt %.4g s, %.3g s, damping %.3g 1/s, %d iterations per step\n", body.c_str(),
                    settle.dt, settle.duration, settle.damping_rate, settle.iterations);
        cloth::single_threaded_blas(); // as the drape command runs
        auto m = std::make_shared<importers::Mannequin>(importers::load_mannequin(body));
        std::printf("%-28s %4s %8s %8s %10s %8s %6s %9s %7s %8s %6s\n", "fabric", "self", "wall_s", "newton", "status", "hem_mm", "folds",
                    "self_int", "inside", "peak_MB", "load");
        double rmin = 1e9, rmax = 0;
        for (const auto& name : fabrics) {
          double wall[2] = {0, 0};
          for (const auto& mode : self_modes) {
            const bool self_on = mode == "on";
            const auto starter = library::find_starter(name);
            const fabric::FabricPreset preset = starter ? *starter : fabric::load_fabric(name);
            importers::Scene scene = importers::make_skirt_scene(m, preset, so);
            if (!self_on) scene.system->model().self_contact_distance = 0;
            cloth::RestOptions ro = importers::garment_rest_options();
            ro.trace = trace;
            if (max_newton > 0) ro.max_newton = max_newton;
            const cloth::SolverStatus st = importers::drape_to_rest(scene, ro, settle);
            const auto& sys = *scene.system;
            const auto gm = importers::garment_metrics(sys.x, sys.mesh().F, sys.model().pinned, m.get(), scene.waist.centre);
            wall[self_on ? 0 : 1] = st.wall_seconds;
            std::printf("%-28s %4s %8.1f %8ld %10s %8.1f %6d %9ld %7d %8ld %6.2f\n", preset.name.c_str(), mode.c_str(), st.wall_seconds, st.newton_iterations,
                        cloth::to_string(st.outcome).c_str(), gm.hem_mean_radius_m * 1e3, gm.hem_fold_count, gm.self_intersections,
                        gm.vertices_inside_body, peak_mb(), load_average());
            if (st.converged()) {
                // Warm: the same skirt with 10 % more bending, from this rest state (as a fit re-solves).
                fabric::FabricPreset stiffer = preset;
                cloth::FabricParams p = stiffer.params;
                p[cloth::Param::BendWarp] *= 1.1;
                p[cloth::Param::BendWeft] *= 1.1;
                stiffer.set_params(p);
                importers::Scene warm = importers::make_skirt_scene(m, stiffer, so);
                if (!self_on) warm.system->model().self_contact_distance = 0;
                warm.system->x = sys.x;
                const cloth::SolverStatus ws = cloth::run_to_rest(*warm.system, ro);
                std::printf("%-28s %4s %8.1f %8ld %10s   (warm: +10 %% bending from the rest state)  %8ld %6.2f\n", "", mode.c_str(), ws.wall_seconds,
                            ws.newton_iterations, cloth::to_string(ws.outcome).c_str(), peak_mb(), load_average());
            }
            if (!st.converged()) {
                std::printf("    %s\n", st.message.c_str());
                if (trace) { // where the unbalanced force sits
                    cloth::Positions f;
                    sys.conservative_forces(sys.x, f);
                    std::vector<std::pair<double, int>> worst;
                    for (int i = 0; i < sys.vertex_count(); ++i)
                        if (!sys.pinned(i)) worst.push_back({f.row(i).norm() / (sys.model().mass(i) * 9.81), i});
                    std::sort(worst.rbegin(), worst.rend());
                    for (int k = 0; k < 12 && k < int(worst.size()); ++k) {
                        const int i = worst[static_cast<std::size_t>(k)].second;
                        importers::ClosestPoint cp;
                        const bool near = m->collider->closest_point(sys.x.row(i).transpose(), cp, 1.0);
                        std::printf("    v%d |f|/mg %.1f z %.3f body distance %.5f m triangle %d\n", i, worst[static_cast<std::size_t>(k)].first,
                                    sys.x(i, 2), near ? m->collider->signed_distance(sys.x.row(i).transpose()) : -1.0,
                                    near ? cp.triangle : -1);
                    }
                }
            }
            std::fflush(stdout);
            rmin = std::min(rmin, gm.hem_mean_radius_m);
            rmax = std::max(rmax, gm.hem_mean_radius_m);
          }
          if (self_modes.size() == 2 && wall[1] > 0)
              std::printf("%-28s wall time self-collision on / off: %.2f\n", name.c_str(), wall[0] / wall[1]);
        }
        if (fabrics.size() > 1) std::printf("widest / narrowest hem: %.3f\n", rmax / rmin);
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_garment: %s\n", e.what());
        return 1;
    }
}
