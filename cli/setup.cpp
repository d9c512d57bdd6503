#include "cli/setup.hpp"

#include "engine/core/error.hpp"
#include "engine/core/text.hpp"
#include "engine/core/units.hpp"

#ifdef HAVE_DRAPE_LIBRARY
#include "engine/library/resolve.hpp"
#endif

#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>

namespace drape::cli {

namespace {
struct FlagName {
    SetupFlag bit;
    const char* name;
    bool is_switch;
};
constexpr FlagName kFlags[] = {
    {kSampleDiameter, "--sample-diameter", false}, {kDiscDiameter, "--disc-diameter", false},
    {kPedestalHeight, "--pedestal-height", false}, {kEdgeRadius, "--edge-radius", false},
    {kGrid, "--grid", false},                      {kSeed, "--seed", false},
    {kFolds, "--folds", false},                    {kPerturbation, "--perturbation", false},
    {kDiscGrip, "--disc-grip", true},              {kLaying, "--laying", false},
    {kMesh, "--mesh", false},                      {kFolds, "--fold-angle", false},
};
} // namespace

std::set<std::string> setup_value_flags(unsigned which)
{
    std::set<std::string> out;
    for (const auto& f : kFlags)
        if ((which & f.bit) && !f.is_switch) out.insert(f.name);
    return out;
}

std::set<std::string> setup_switches(unsigned which)
{
    std::set<std::string> out;
    for (const auto& f : kFlags)
        if ((which & f.bit) && f.is_switch) out.insert(f.name);
    return out;
}

std::set<std::string> operator+(std::set<std::string> a, const std::set<std::string>& b)
{
    a.insert(b.begin(), b.end());
    return a;
}

double parse_laying(const Args& a, double fallback) { return a.get_double_in("--laying", fallback, 1e-3, 1.0); }

double parse_perturbation(const Args& a, double fallback)
{
    const double v = a.get_length("--perturbation", fallback);
    if (!(v >= 0) || v > 0.05)
        throw UsageError("--perturbation " + *a.get("--perturbation") + " is outside [0, 50mm] (the flat start's largest lift)");
    return v;
}

cloth::DrapeMesh parse_mesh(const Args& a, cloth::DrapeMesh fallback)
{
    const auto m = a.get("--mesh");
    if (!m) return fallback;
    try {
        return cloth::drape_mesh_from_string(*m);
    } catch (const Error& e) {
        throw UsageError(std::string("--") + e.what());
    }
}

cloth::DrapeMesh preset_mesh(const Args& a, const fabric::FabricPreset& preset)
{
    if (a.has("--mesh") || !preset.provenance || !preset.provenance->details.contains("mesh")) return parse_mesh(a, cloth::DrapeMesh::Grid);
    const auto& m = preset.provenance->details["mesh"];
    const std::string where = a.get("--fabric").value_or("the preset") + ": provenance.";
    if (!m.is_string()) throw ParameterError(where + "mesh must be \"grid\" or \"rings\", not " + m.dump());
    try {
        return cloth::drape_mesh_from_string(m.get<std::string>());
    } catch (const Error& e) {
        throw ParameterError(where + e.what());
    }
}

std::optional<int> preset_fit_grid(const fabric::FabricPreset& preset, double sample_diameter)
{
    if (!preset.provenance || preset.provenance->grid <= 0) return std::nullopt;
    const double fit_D1 = preset.fit && preset.fit->sample_diameter_m > 0 ? preset.fit->sample_diameter_m : 0.30;
    return static_cast<int>(std::lround(preset.provenance->grid * sample_diameter / fit_D1));
}

cloth::DrapeSetup parse_setup(const Args& a, cloth::DrapeSetup s)
{
    s.sample_diameter = a.get_length("--sample-diameter", s.sample_diameter);
    s.disc_diameter = a.get_length("--disc-diameter", s.disc_diameter);
    s.pedestal_height = a.get_length("--pedestal-height", s.pedestal_height);
    s.edge_radius = a.get_length("--edge-radius", s.edge_radius);
    s.grid = a.get_int("--grid", s.grid, 5, 1000);
    s.mesh = parse_mesh(a, s.mesh);
    s.seed = static_cast<std::uint64_t>(a.get_int("--seed", static_cast<int>(s.seed), 0, 2000000000));
    if (a.has("--fold-angle") && !a.has("--folds")) throw UsageError("--fold-angle needs --folds (the angle of one of the N-fold start's crests)");
    if (a.has("--folds")) {
        const int folds = a.get_int("--folds", 0, 2, 16); // parsed first: its error comes first
        const double angle = a.has("--fold-angle") ? a.get_double_in("--fold-angle", 0, -360, 360, "deg") * std::numbers::pi / 180
                                                   : std::numeric_limits<double>::quiet_NaN();
        s = cloth::on_fold_branch(s, folds, cloth::kFoldBranchLift, angle);
    }
    s.perturbation = a.get_length("--perturbation", s.perturbation);
    if (a.has("--disc-grip")) s.disc_grip = true;
    if (a.has("--folds")) s.laying_load = 1.0; // a prescribed branch starts under the whole load
    s.laying_load = parse_laying(a, s.laying_load);
    s.validate();
    return s;
}

std::set<std::string> fabric_flags() { return {"--fabric", "--set"}; }

fabric::FabricPreset load_fabric_flags(const Args& a, const std::string& fallback)
{
    auto arg = a.get("--fabric");
    if (!arg && !fallback.empty()) arg = fallback;
    if (!arg) throw UsageError("--fabric is required");
#ifdef HAVE_DRAPE_LIBRARY
    fabric::FabricPreset preset = library::resolve_fabric(*arg);
#else
    fabric::FabricPreset preset = fabric::load_fabric(*arg);
#endif
    if (a.get_all("--set").empty()) return preset;
    to_continuum(preset, apply_set_flags(a, preset.params), "--set");
    return preset;
}

void to_continuum(fabric::FabricPreset& preset, const cloth::FabricParams& p, const std::string& flag)
{
    if (preset.seed)
        std::fprintf(stderr,
                     "note: %s turns the seed-19 preset '%s' into its continuum equivalent (stretch, shear, mass and dampers "
                     "from its grid springs; bending the parameter table's default unless --set gives it: flexion springs "
                     "have no continuum counterpart), draped on the command's grid, not on its own %d nodes across "
                     "(\"fabric_model\": \"continuum\" in --json)\n",
                     flag.c_str(), printable(preset.name).c_str(), preset.seed->u + 1);
    preset.set_params(p);
}

cloth::DrapeSetup on_preset_grid(const Args& a, const fabric::FabricPreset& preset, cloth::DrapeSetup s)
{
    if (!preset.seed) return s;
    const int own = preset.seed->u + 1;
    if (a.has("--grid") && s.grid != own)
        throw UsageError("--grid " + std::to_string(s.grid) + ": '" + printable(preset.name) +
                         "' is a seed-19 preset, whose 19 constants are the springs of its own " + std::to_string(preset.seed->u) +
                         " x " + std::to_string(preset.seed->v) + " cell grid (" + std::to_string(own) +
                         " nodes across); it drapes on that grid only. Leave --grid out, or --set a parameter to drape its "
                         "continuum equivalent on any grid");
    s.grid = own;
    return s;
}

const char* fabric_model_name(const fabric::FabricPreset& preset) { return preset.seed ? "seed-19" : "continuum"; }

cloth::FabricParams apply_set_flags(const Args& a, cloth::FabricParams p)
{
    for (const auto& kv : a.get_all("--set")) {
        const auto eq = kv.find('=');
        if (eq == std::string::npos) throw UsageError("--set: '" + kv + "' is not KEY=VALUE (e.g. --set bend_warp_Nm=2e-6)");
        const std::string key = kv.substr(0, eq), text = kv.substr(eq + 1);
        const cloth::ParamSpec* sp = cloth::find_param(key);
        if (!sp) {
            std::string keys;
            for (const auto& s : cloth::param_table()) keys += (keys.empty() ? "" : ", ") + std::string(s.key);
            throw UsageError("--set: unknown parameter '" + key + "' (one of " + keys + ")");
        }
        double v = 0;
        if (!parse_number(text, v)) throw UsageError("--set " + key + ": '" + text + "' is not a number (in " + std::string(sp->unit) + ")");
        if (v < sp->lower || v > sp->upper)
            throw UsageError("--set " + key + " = " + format_value(v) + " " + std::string(sp->unit) + " is outside [" +
                             format_value(sp->lower) + ", " + format_value(sp->upper) + "]");
        p[sp->id] = v;
    }
    return p;
}

std::vector<std::string> split_list(const std::string& list)
{
    std::vector<std::string> out;
    std::size_t pos = 0;
    while (true) {
        const std::size_t c = list.find(',', pos);
        out.push_back(list.substr(pos, c == std::string::npos ? std::string::npos : c - pos));
        if (c == std::string::npos) return out;
        pos = c + 1;
    }
}

} // namespace drape::cli
