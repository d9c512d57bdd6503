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
#include "engine/estimate/predict.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>

namespace drape::cli {
namespace cmd_predict {

const char* kUsage = R"(usage: drape predict --fabric FABRIC.json --sample-diameter L --disc-diameter L [options]

Predicts the drape of a (fitted) preset on a set-up it was not fitted to, e.g.
360/180 mm from a fit at 300/150: draped from flat as its fit's lab laid its
specimens, with several perturbation seeds, D and the fold count with a 95 %
interval. Prints the same keys as `drape simulate` (the first drape's, with D
and the fold count the prediction's) plus drape_coefficient_interval_percent,
node_count_range and prediction.

  --fabric F            preset file (drapekit-fabric or seed-19 JSON), seed-table1, a fabric of the
                        library, or a starter fabric: silk, cotton, wool, denim
  --set KEY=VALUE       override one parameter (a key of the parameter table; repeatable)
  --sample-diameter L   specimen diameter (default 300mm; units mm, cm, m; bare = m)
  --disc-diameter L     pedestal disc diameter (default 150mm)
  --pedestal-height L   pedestal height (default 120mm)
  --areal-density G     override the preset's areal density [g/m^2] (another cut of the fabric)
  --grid N              nodes across the specimen (default: the fit's grid scaled to the new
                        diameter when the preset carries provenance, within 9..201, else 31; a
                        seed-19 preset drapes on its own grid, u + 1 nodes across, and refuses another)
  --mesh M              grid | rings (default: the fit's, provenance.mesh, else grid; see
                        drape simulate --help)
  --seed K              the first drape's perturbation seed (default 1)
  --seeds N             drapes from flat, seeds K .. K+N-1 (default 3): D is their mean, the fold
                        count their median
  --no-interval         no 95 % interval (by default D comes with one, from the fit's covariance
                        through the exact sensitivity of D, the spread over the drapes and the
                        drape-to-drape spread of real repeats, 2.5 points, and on a set-up the preset
                        was not fitted on 47 % of the change of D from the nearest fitted record; the
                        fold count with the range the drapes laid, widened by one fold)
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


int run(const std::vector<std::string>& argv)
{
    Args a(argv, fabric_flags() + setup_value_flags(kAllSetup) + std::set<std::string>{"--areal-density", "--seeds"},
           setup_switches(kAllSetup) + std::set<std::string>{"--json", "--quiet", "--no-interval"});
    if (!a.positionals().empty()) throw UsageError("unexpected argument '" + a.positionals().front() + "'");
    fabric::FabricPreset preset = load_fabric_flags(a);
    if (a.has("--areal-density")) {
        // In g/m^2 on the command line; the table's bounds are kg/m^2.
        const cloth::ParamSpec& sp = cloth::spec(cloth::Param::AreaDensity);
        cloth::FabricParams p = preset.params;
        p[cloth::Param::AreaDensity] = a.get_double_in("--areal-density", 0, sp.lower * 1e3, sp.upper * 1e3, "g/m^2") * 1e-3;
        to_continuum(preset, p, "--areal-density");
    }
    // The fit's lab's laying and waviness, its mesh and its grid scaled with the
    // diameter (the same mesh density: the fit's bias is then the same), as the
    // transfer benchmark predicts (estimate::prediction_setup).
    cloth::DrapeSetup defaults;
    defaults.sample_diameter = a.get_length("--sample-diameter", defaults.sample_diameter);
    defaults.grid = 0;
    defaults = estimate::prediction_setup(preset, defaults);
    defaults.mesh = preset_mesh(a, preset); // --mesh, else the fit's
    const cloth::DrapeSetup setup = on_preset_grid(a, preset, parse_setup(a, defaults));
    cloth::single_threaded_blas();
    estimate::PredictOptions po;
    po.seeds = a.get_int("--seeds", po.seeds, 1, 32);
    po.intervals = !a.has("--no-interval");
    const bool json = a.has("--json"), quiet = a.has("--quiet") || json;
    Progress progress("predict", quiet);
    if (!quiet) {
        po.rest.progress = progress.solver_callback(po.rest);
        po.on_drape = [&progress, &setup](int k, int n) {
            progress.update(-1.0, "drape " + std::to_string(k + 1) + " of " + std::to_string(n) + " (seed " +
                                      std::to_string(setup.seed + static_cast<std::uint64_t>(k)) + ")", true);
        };
    }
    const estimate::Prediction pr = estimate::predict_drape(preset, setup, po);
    const cloth::DrapeResult& r = pr.drapes.front();
    progress.finish(pr.converged ? "converged" : "not at rest", pr.converged);
    for (const auto& d : pr.drapes)
        if (!check_drape_result(d, setup)) return 4;
    const bool interval = po.intervals && std::isfinite(pr.dc_lower95);
    if (json) {
        // simulate's summary of the first drape, with D and the fold count the
        // prediction's (the mean and the median over the drapes) and their ranges.
        nlohmann::json j = cloth::drape_summary_json(r, setup, po.rest.integrator);
        j["fabric_model"] = fabric_model_name(preset); // as simulate's summary
        j["bending_correction"] = preset.model.bending_correction && setup.mesh == cloth::DrapeMesh::Grid;
        j["arc_membrane"] = preset.model.arc_membrane;
        j["converged"] = pr.converged;
        j["drape_coefficient_percent"] = pr.dc_percent;
        j["node_count"] = pr.node_count;
        j["drape_coefficient_interval_percent"] = interval ? nlohmann::json::array({pr.dc_lower95, pr.dc_upper95}) : nlohmann::json(nullptr);
        j["node_count_range"] = nlohmann::json::array({pr.nodes_lower, pr.nodes_upper});
        nlohmann::json per_d = nlohmann::json::array(), per_n = nlohmann::json::array();
        for (const auto& d : pr.drapes) {
            per_d.push_back(d.metrics.drape_coefficient_percent);
            per_n.push_back(d.metrics.node_count);
        }
        j["prediction"] = {{"seeds", static_cast<int>(pr.drapes.size())},
                           {"drape_coefficients_percent", per_d},
                           {"node_counts", per_n},
                           {"sigma_parameters_percent", pr.sigma_parameters_percent},
                           {"sigma_starts_percent", pr.sigma_starts_percent},
                           {"sigma_repeat_percent", pr.sigma_repeat_percent},
                           {"sigma_transfer_percent", pr.sigma_transfer_percent},
                           {"transfer_from", pr.transfer_from.empty() ? nlohmann::json(nullptr) : nlohmann::json(pr.transfer_from)},
                           {"transfer_change_percent", pr.transfer_from.empty() ? nlohmann::json(nullptr) : nlohmann::json(pr.transfer_change_percent)},
                           {"fitted_setup", pr.fitted_setup},
                           {"parameters_known", pr.parameters_known},
                           {"interval_level", 0.95},
                           {"wall_seconds", pr.wall_seconds}};
        std::cout << dump_json(j) << "\n";
    } else {
        std::string how = setup.laying_load < 1 ? ", laid under " + format_value(setup.laying_load) + " g first" : std::string();
        if (setup.fold_mode == 0 && setup.perturbation != cloth::kStartLift) how += ", " + format_value(setup.perturbation * 1e3) + " mm wavy";
        std::printf("set-up             %.0f / %.0f mm (grid %d, seeds %llu..%llu%s)\n", setup.sample_diameter * 1e3, setup.disc_diameter * 1e3,
                    setup.grid, static_cast<unsigned long long>(setup.seed),
                    static_cast<unsigned long long>(setup.seed + pr.drapes.size() - 1), how.c_str());
        std::printf("drape coefficient  %.1f %%", pr.dc_percent);
        if (interval) std::printf("  (95 %%: %.1f .. %.1f %%)", pr.dc_lower95, pr.dc_upper95);
        std::printf("\n");
        std::printf("nodes              %d  (%d .. %d)\n", pr.node_count, pr.nodes_lower, pr.nodes_upper);
        if (interval) {
            char par[64] = "not known (no fit covariance)";
            if (pr.parameters_known) std::snprintf(par, sizeof par, "%.1f", pr.sigma_parameters_percent);
            std::printf("interval terms     fitted parameters %s, starts %.1f, drape to drape %.1f", par, pr.sigma_starts_percent,
                        pr.sigma_repeat_percent);
            if (pr.sigma_transfer_percent > 0)
                std::printf(", transfer %.1f (%.0f %% of the %+.1f points from %s, the nearest fitted set-up)", pr.sigma_transfer_percent,
                            100 * po.transfer_fraction, pr.transfer_change_percent, pr.transfer_from.c_str());
            std::printf(" points (1 sigma)\n");
        }
        std::printf("hem height         %.1f .. %.1f mm (below the pedestal top; seed %llu)\n", r.hem.min_z * 1e3, r.hem.max_z * 1e3,
                    static_cast<unsigned long long>(setup.seed));
        std::printf("solver             %s, %.2f s for %zu drapes\n", pr.converged ? "converged" : "not at rest", pr.wall_seconds, pr.drapes.size());
    }
    return pr.converged ? 0 : 4;
}

} // namespace cmd_predict

DRAPE_COMMAND({"predict", "predict the drape of a fitted preset on another set-up (same JSON as simulate)", cmd_predict::kUsage, cmd_predict::run});

} // namespace drape::cli
