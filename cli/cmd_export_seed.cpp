// drape export-seed: a drapekit-fabric preset as the seed paper's 19 grid constants.
#include "cli/command.hpp"
#include "cli/setup.hpp"

#include "engine/core/error.hpp"
#include "engine/fabric/preset.hpp"
#include "engine/cloth/blas_threads.hpp"
#include "engine/core/io.hpp"
#include "engine/estimate/seed_export.hpp"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <iostream>

namespace drape::cli {
namespace cmd_export_seed {

const char* kUsage = R"(usage: drape export-seed --fabric FABRIC.json --out SEED.json [options]

Writes a drapekit-fabric preset as the seed paper's 19 grid constants (format
seed-19) for one grid. Mass, structural and shear springs and dampers follow
exactly; the flexion springs have no continuum counterpart and are calibrated so
that the seed model drapes to the preset's drape coefficient on the same set-up
and grid (several simulations; the result says how close it came).

  --fabric F            drapekit-fabric preset (e.g. from drape fit)
  --set KEY=VALUE       override one parameter (a key of the parameter table; repeatable)
  --out FILE            seed-19 JSON to write
  --grid N              nodes across the specimen, i.e. N - 1 seed patches (default: the
                        fit's grid from the preset's provenance, else 31 = the seed's 30)
  --sample-diameter L   specimen diameter (default 300mm; units mm, cm, m; bare = m)
  --disc-diameter L     pedestal disc diameter of the calibration drape (default 150mm)
  --seeds S             perturbation seeds per drape coefficient (default 2)
  --json                print a JSON summary on stdout
  --quiet               no progress on stderr
Exit code 3 (file still written) when the seed model cannot reach the preset's D.)";

int run(const std::vector<std::string>& argv)
{
    Args a(argv, fabric_flags() + setup_value_flags(kGrid | kSampleDiameter | kDiscDiameter) + std::set<std::string>{"--out", "--seeds"},
           {"--json", "--quiet"});
    if (!a.positionals().empty()) throw UsageError("unexpected argument '" + a.positionals().front() + "'");
    const auto out = a.get("--out");
    if (!out) throw UsageError("--out SEED.json is required");
    prepare_output_file(*out, "--out");
    const fabric::FabricPreset preset = load_fabric_flags(a);
    const std::string fabric_arg = *a.get("--fabric");
    if (preset.is_seed()) throw UsageError("--fabric " + fabric_arg + " is already a seed-19 preset");
    const cloth::FabricParams* p = &preset.params;
    cloth::DrapeSetup defaults;
    defaults.grid = preset.provenance && preset.provenance->grid > 0 ? preset.provenance->grid : 31;
    defaults = preset.laid(defaults); // the D `drape simulate` gives the preset: laid and started as its lab
    const cloth::DrapeSetup setup = parse_setup(a, defaults);
    if (setup.grid > 401) throw UsageError("--grid: " + std::to_string(setup.grid) + " is outside [5, 401]");
    const int seeds = a.get_int("--seeds", 2, 1, 16);
    const bool json = a.has("--json"), quiet = a.has("--quiet") || json;
    cloth::single_threaded_blas();
    const estimate::SeedExport e = estimate::export_seed(*p, setup, preset.model, seeds, 0.5, [&](const std::string& s) {
        if (!quiet) std::fprintf(stderr, "  %s\n", s.c_str());
    });
    nlohmann::json j = fabric::seed_to_json(e.seed);
    j["name"] = preset.name.empty() ? std::string("exported") : preset.name;
    j["exported_from"] = {{"preset", fabric_arg},
                          {"grid", setup.grid},
                          {"sample_diameter_m", setup.sample_diameter},
                          {"disc_diameter_m", setup.disc_diameter},
                          {"seeds", seeds},
                          {"laying_load", setup.laying_load},      // the drapes it matched were laid so
                          {"perturbation_m", setup.perturbation}, // and started this wavy (the preset's lab)
                          {"preset_drape_coefficient_percent", e.target_dc_percent},
                          {"seed_drape_coefficient_percent", e.seed_dc_percent},
                          {"matched", e.matched},
                          {"simulations", e.simulations},
                          {"note", e.note}};
    drape::write_file_atomic(*out, cli::dump_json(j) + "\n");
    if (json) {
        std::cout << cli::dump_json(j) << "\n";
    } else {
        std::printf("seed-19 constants for %d x %d patches written to %s\n", e.seed.u, e.seed.v, out->c_str());
        std::printf("drape coefficient  preset %.1f %%, seed constants %.1f %% (%s)\n", e.target_dc_percent, e.seed_dc_percent,
                    e.matched ? "matched" : "NOT matched");
        if (!e.note.empty()) std::printf("note               %s\n", e.note.c_str());
        std::printf("flexion            SflKu %.4g, SflKv %.4g N/m (calibrated on D); %d simulations\n", e.seed.sfl_ku, e.seed.sfl_kv,
                    e.simulations);
    }
    return e.matched ? 0 : 3;
}

} // namespace cmd_export_seed

DRAPE_COMMAND({"export-seed", "write a fabric preset as the seed paper's 19 grid constants for one grid", cmd_export_seed::kUsage, cmd_export_seed::run});

} // namespace drape::cli
