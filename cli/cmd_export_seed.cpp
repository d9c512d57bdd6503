// drape export-seed: a drapekit-fabric preset as the seed paper's 19 grid constants.
#include "command.hpp"

#include "engine/cloth/error.hpp"
#include "engine/cloth/fabric_io.hpp"
#include "engine/estimate/fit.hpp"
#include "engine/estimate/seed_export.hpp"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <iostream>

namespace drape::cli {
namespace {

const char* kUsage = R"(usage: drape export-seed --fabric FABRIC.json --out SEED.json [options]

Writes a drapekit-fabric preset as the seed paper's 19 grid constants (format
seed-19) for one grid. Mass, structural and shear springs and dampers follow
exactly; the flexion springs have no continuum counterpart and are calibrated so
that the seed model drapes to the preset's drape coefficient on the same set-up
and grid (several simulations; the result says how close it came).

  --fabric F            drapekit-fabric preset (e.g. from drape fit)
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
    Args a(argv, {"--fabric", "--out", "--grid", "--sample-diameter", "--disc-diameter", "--seeds"}, {"--json", "--quiet"});
    if (!a.positionals().empty()) throw UsageError("unexpected argument '" + a.positionals().front() + "'");
    const auto fabric_arg = a.get("--fabric");
    if (!fabric_arg) throw UsageError("--fabric is required");
    const auto out = a.get("--out");
    if (!out) throw UsageError("--out SEED.json is required");
    prepare_output_file(*out, "--out");
    const cloth::FabricPreset preset = cloth::load_fabric(*fabric_arg);
    const auto* p = std::get_if<cloth::FabricParams>(&preset.fabric);
    if (!p) throw UsageError("--fabric " + *fabric_arg + " is already a seed-19 preset");
    int grid = 31;
    if (preset.extra.contains("provenance") && preset.extra["provenance"].contains("grid") && preset.extra["provenance"]["grid"].is_number_integer())
        grid = preset.extra["provenance"]["grid"].get<int>();
    cloth::DrapeSetup setup;
    setup.grid = a.get_int("--grid", grid, 5, 401);
    setup.sample_diameter = a.get_length("--sample-diameter", 0.30);
    setup.disc_diameter = a.get_length("--disc-diameter", 0.15);
    setup.validate();
    const int seeds = a.get_int("--seeds", 2, 1, 16);
    const bool json = a.has("--json"), quiet = a.has("--quiet") || json;
    estimate::single_threaded_blas();
    const estimate::SeedExport e = estimate::export_seed(*p, setup, preset.model, seeds, 0.5, [&](const std::string& s) {
        if (!quiet) std::fprintf(stderr, "  %s\n", s.c_str());
    });
    nlohmann::json j = cloth::seed_to_json(e.seed);
    j["name"] = p->name.empty() ? std::string("exported") : p->name;
    j["exported_from"] = {{"preset", *fabric_arg},
                          {"grid", setup.grid},
                          {"sample_diameter_m", setup.sample_diameter},
                          {"disc_diameter_m", setup.disc_diameter},
                          {"seeds", seeds},
                          {"preset_drape_coefficient_percent", e.target_dc_percent},
                          {"seed_drape_coefficient_percent", e.seed_dc_percent},
                          {"matched", e.matched},
                          {"simulations", e.simulations},
                          {"note", e.note}};
    cloth::write_file_atomic(*out, j.dump(2) + "\n");
    if (json) {
        std::cout << j.dump(2) << "\n";
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

} // namespace

DRAPE_COMMAND({"export-seed", "write a fabric preset as the seed paper's 19 grid constants for one grid", kUsage, run});

} // namespace drape::cli
