// drape predict: simulate a fitted preset on another drape set-up.
#include "cli/command.hpp"
#include "cli/checks.hpp"
#include "cli/progress.hpp"
#include "cli/setup.hpp"
#include "engine/core/units.hpp"

#include "engine/cloth/drape_io.hpp"
#include "engine/core/error.hpp"
#include "engine/fabric/preset.hpp"
#include "engine/cloth/blas_threads.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>

namespace drape::cli {
namespace {

const char* kUsage = R"(usage: drape predict --fabric FABRIC.json --sample-diameter L --disc-diameter L [options]

Predicts the drape of a (fitted) preset on a set-up it was not fitted to, e.g.
360/180 mm from a fit at 300/150. Prints the same keys as `drape simulate`.

  --fabric F            preset file (drapekit-fabric or seed-19 JSON), seed-table1, a fabric of the
                        library, or a starter fabric: silk, cotton, wool, denim
  --set KEY=VALUE       override one parameter (a key of the parameter table; repeatable)
  --sample-diameter L   specimen diameter (default 300mm; units mm, cm, m; bare = m)
  --disc-diameter L     pedestal disc diameter (default 150mm)
  --pedestal-height L   pedestal height (default 120mm)
  --areal-density G     override the preset's areal density [g/m^2] (another cut of the fabric)
  --grid N              nodes across the specimen (default: the fit's grid scaled to the new
                        diameter when the preset carries provenance, within 9..201, else 31)
  --mesh M              grid | rings (default: the fit's, provenance.mesh, else grid; see
                        drape simulate --help)
  --seed K              perturbation seed (default 1)
  --folds N             start on an N-fold branch (a 5 mm N-fold lift; default: the seeded mix)
  --fold-angle DEG      with --folds: one crest of the lift this far from the warp (default: seeded)
  --laying F            how the specimen is laid: it first rests under the fraction F of gravity, then
                        under all of it (default: the preset's provenance.laying_load, what its fit
                        assumed of its records' lab - drape fit: 0.4 -, else 1 = the whole load at
                        once; 1 with --folds unless --laying is given). Static solver only: the
                        dynamic integrators fall under the whole load
  --perturbation L      the largest lift of the flat start's seeded waviness (default: the preset's
                        provenance.perturbation_m, how wavy its fit assumed its lab laid it - drape
                        fit: 6mm -, else 1mm; at most 50mm)
  --json                print the summary as JSON on stdout
  --quiet               no progress on stderr)";

/// Range of the grid predict derives from a fit's (odd, so the centre is a node).
constexpr int kMinDefaultGrid = 9;
constexpr int kMaxDefaultGrid = 201;

int run(const std::vector<std::string>& argv)
{
    Args a(argv, fabric_flags() + setup_value_flags(kAllSetup) + std::set<std::string>{"--areal-density"},
           setup_switches(kAllSetup) + std::set<std::string>{"--json", "--quiet"});
    if (!a.positionals().empty()) throw UsageError("unexpected argument '" + a.positionals().front() + "'");
    fabric::FabricPreset preset = load_fabric_flags(a);
    if (a.has("--areal-density")) {
        // In g/m^2 on the command line; the table's bounds are kg/m^2.
        const cloth::ParamSpec& sp = cloth::spec(cloth::Param::AreaDensity);
        cloth::FabricParams p = preset.params;
        p[cloth::Param::AreaDensity] = a.get_double_in("--areal-density", 0, sp.lower * 1e3, sp.upper * 1e3, "g/m^2") * 1e-3;
        preset.set_params(p);
    }
    cloth::DrapeSetup defaults;
    defaults = preset.laid(defaults); // a fitted preset is laid (and as wavy) as its records' lab laid them
    defaults.sample_diameter = a.get_length("--sample-diameter", defaults.sample_diameter);
    // Same mesh density as the fit (the fit's bias is then the same): the fit's
    // grid scaled with the diameter.
    defaults.grid = 31;
    if (const auto g = preset_fit_grid(preset, defaults.sample_diameter)) {
        defaults.grid = *g % 2 == 0 ? *g + 1 : *g;
        // A default, not the user's --grid: kept inside what --grid takes
        // rather than failing on a flag that was never given.
        defaults.grid = std::clamp(defaults.grid, kMinDefaultGrid, kMaxDefaultGrid);
    }
    // The fit's mesh too (provenance.mesh since 2026-12-01; grid before), unless --mesh says.
    defaults.mesh = preset_mesh(a, preset);
    const cloth::DrapeSetup setup = parse_setup(a, defaults);
    cloth::single_threaded_blas();
    cloth::RestOptions ro;
    const bool json = a.has("--json"), quiet = a.has("--quiet") || json;
    Progress progress("predict", quiet);
    if (!quiet) ro.progress = progress.solver_callback(ro);
    const cloth::DrapeResult r = cloth::simulate_drape(preset.material(), setup, ro, preset.model);
    progress.finish(to_string(r.status.outcome), r.status.converged());
    if (!check_drape_result(r, setup)) return 4;
    if (json) {
        nlohmann::json j = cloth::drape_summary_json(r, setup, ro.integrator);
        j["bending_correction"] = preset.model.bending_correction && setup.mesh == cloth::DrapeMesh::Grid; // as simulate's summary
        j["arc_membrane"] = preset.model.arc_membrane;
        std::cout << dump_json(j) << "\n";
    } else {
        std::string how = setup.laying_load < 1 ? ", laid under " + format_value(setup.laying_load) + " g first" : std::string();
        if (setup.fold_mode == 0 && setup.perturbation != cloth::kStartLift) how += ", " + format_value(setup.perturbation * 1e3) + " mm wavy";
        std::printf("set-up             %.0f / %.0f mm (grid %d, seed %llu%s)\n", setup.sample_diameter * 1e3, setup.disc_diameter * 1e3,
                    setup.grid, static_cast<unsigned long long>(setup.seed), how.c_str());
        std::printf("drape coefficient  %.1f %%\n", r.metrics.drape_coefficient_percent);
        std::printf("nodes              %d\n", r.metrics.node_count);
        std::printf("hem height         %.1f .. %.1f mm (below the pedestal top)\n", r.hem.min_z * 1e3, r.hem.max_z * 1e3);
        std::printf("solver             %s, %ld iterations, %.2f s\n", to_string(r.status.outcome).c_str(), r.status.steps,
                    r.status.wall_seconds);
    }
    return r.status.converged() ? 0 : 4;
}

} // namespace

DRAPE_COMMAND({"predict", "predict the drape of a fitted preset on another set-up (same JSON as simulate)", kUsage, run});

} // namespace drape::cli
