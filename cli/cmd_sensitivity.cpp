// drape sensitivity: one parameter at a time around a preset (seed paper's study).
#include "cli/command.hpp"
#include "cli/setup.hpp"

#include "engine/core/error.hpp"
#include "engine/fabric/preset.hpp"
#include "engine/estimate/sensitivity.hpp"

#include <cstdio>

namespace drape::cli {
namespace cmd_sensitivity {

const char* kUsage = R"(usage: drape sensitivity --fabric FABRIC.json --out DIR [options]

Varies one parameter at a time around the preset (log parameters by 10^(-span..+span),
others by +-50 % of their range) and records D, node count, hem height and the
harmonic magnitudes of the shadow outline: DIR/sensitivity.csv and two PNG plots
per parameter.

  --fabric F            a drapekit-fabric preset: file, library name or starter (silk, cotton, ...)
  --set KEY=VALUE       override one parameter (a key of the parameter table; repeatable)
  --out DIR             output folder
  --params K,K,...      parameter keys (default bend_warp_Nm,bend_weft_Nm,shear_N_m,
                        stretch_warp_N_m,stretch_weft_N_m,areal_density_kg_m2)
  --steps N             values per parameter (default 5)
  --span DECADES        range of log parameters (default 1)
  --sample-diameter L   (default 300mm)   --disc-diameter L (default 150mm)
  --grid N              (default 25)      --seed K (default 1)
  --mesh M              grid (default) | rings
  --quiet               no progress on stderr)";

int run(const std::vector<std::string>& argv)
{
    Args a(argv,
           fabric_flags() + setup_value_flags(kSampleDiameter | kDiscDiameter | kGrid | kSeed | kMesh) +
               std::set<std::string>{"--out", "--params", "--steps", "--span"},
           {"--quiet"});
    if (!a.positionals().empty()) throw UsageError("unexpected argument '" + a.positionals().front() + "'");
    const auto out = a.get("--out");
    if (!out) throw UsageError("--out DIR is required");
    const fabric::FabricPreset preset = load_fabric_flags(a);
    if (preset.is_seed()) throw UsageError("sensitivity needs a drapekit-fabric (continuum) preset, not seed-19");
    const cloth::FabricParams* base = &preset.params;
    estimate::SensitivityOptions o;
    o.model = preset.model;
    cloth::DrapeSetup defaults;
    defaults.grid = 25;
    defaults = preset.laid(defaults); // laid and started as `drape simulate` lays the preset
    o.setup = parse_setup(a, defaults);
    if (o.setup.grid > 200) throw UsageError("--grid: " + std::to_string(o.setup.grid) + " is outside [5, 200]");
    o.steps = a.get_int("--steps", 5, 2, 41);
    o.span_decades = a.get_double("--span", 1.0);
    if (const auto ps = a.get("--params")) {
        o.params.clear();
        for (const auto& key : split_list(*ps)) {
            const cloth::ParamSpec* sp = cloth::find_param(key);
            if (!sp) throw UsageError("--params: unknown parameter '" + key + "'");
            if (!sp->affects_statics) throw UsageError("--params: '" + key + "' is a damper; it does not change the rest state");
            o.params.push_back(sp->id);
        }
    }
    if (!a.has("--quiet"))
        o.progress = [](int done, int total) {
            std::fprintf(stderr, "\r  %d/%d drapes", done, total);
            std::fflush(stderr);
        };
    const auto rows = estimate::sensitivity_study(*base, o);
    if (!a.has("--quiet")) std::fprintf(stderr, "\n");
    const auto files = estimate::write_sensitivity(rows, *base, *out);
    std::printf("%-22s %12s %8s %6s\n", "parameter", "value", "D [%]", "nodes");
    for (const auto& r : rows)
        std::printf("%-22s %12.4g %8.1f %6d%s\n", std::string(cloth::spec(r.param).key).c_str(), r.value, r.drape_coefficient_percent,
                    r.node_count, r.converged ? "" : "  (not converged)");
    std::printf("%zu files in %s\n", files.size(), out->c_str());
    return 0;
}

} // namespace cmd_sensitivity

DRAPE_COMMAND({"sensitivity", "vary one parameter at a time and plot D, nodes and harmonics", cmd_sensitivity::kUsage, cmd_sensitivity::run});

} // namespace drape::cli
