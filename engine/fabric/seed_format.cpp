#include "engine/fabric/seed_format.hpp"

#include "engine/core/error.hpp"
#include "engine/core/json_reader.hpp"
#include "engine/core/units.hpp"

#include <cmath>

namespace drape::fabric {

using nlohmann::json;

double SeedParams::hu_m() const { return w * 0.01 / u; }
double SeedParams::hv_m() const { return h * 0.01 / v; }
double SeedParams::particle_mass_kg() const { return kSeedMassUnitKg / cloth_over_mass; }

void SeedParams::validate(const std::string& where) const
{
    // Ranges of the seed fields themselves; what they add up to is checked
    // against the parameter table below.
    auto in_range = [&](const char* name, double x, double lo, double hi, const char* unit, bool open_low) {
        if (!std::isfinite(x) || (open_low ? !(x > lo) : x < lo) || x > hi)
            throw ParameterError(where + ": field '" + name + "' = " + format_value(x) + " " + unit + " is outside " +
                                 (open_low ? "(" : "[") + format_value(lo) + ", " + format_value(hi) + "] " + unit);
    };
    in_range("w", w, 0, kMaxSeedSizeCm, "cm", true);
    in_range("h", h, 0, kMaxSeedSizeCm, "cm", true);
    // The engine drapes a seed preset on its own grid: at most what --grid allows.
    if (u < 4 || u > kMaxSeedCells) throw ParameterError(where + ": field 'u' = " + std::to_string(u) + " must be in [4, " + std::to_string(kMaxSeedCells) + "]");
    if (v < 4 || v > kMaxSeedCells) throw ParameterError(where + ": field 'v' = " + std::to_string(v) + " must be in [4, " + std::to_string(kMaxSeedCells) + "]");
    for (auto [n, x] : {std::pair{"x0", x0}, {"y0", y0}, {"z0", z0}}) in_range(n, x, -kMaxSeedSizeCm, kMaxSeedSizeCm, "cm", false);
    in_range("ClothOverMass", cloth_over_mass, 0, 1e12, "1/(0.01 g)", true);
    for (auto [n, x] : {std::pair{"SstKu", sst_ku}, {"SstKv", sst_kv}}) in_range(n, x, 0, kMaxSeedSpring, "N/m", true);
    for (auto [n, x] : {std::pair{"SshK", ssh_k}, {"SflKu", sfl_ku}, {"SflKv", sfl_kv}}) in_range(n, x, 0, kMaxSeedSpring, "N/m", false);
    for (auto [n, x] : {std::pair{"SstDu", sst_du}, {"SstDv", sst_dv}, {"SshD", ssh_d}, {"SflDu", sfl_du}, {"SflDv", sfl_dv}})
        in_range(n, x, 0, kMaxSeedDamper, "N*s/m", false);
    // The continuum equivalent must be a fabric the table accepts (a weight of
    // 1e302 g/m^2 is a typo, not a fabric); the message names the seed fields
    // that make the value.
    const cloth::FabricParams p = continuum_from_seed(*this);
    for (const auto& sp : cloth::param_table()) {
        const double x = p[sp.id];
        if (std::isfinite(x) && x >= sp.lower && x <= sp.upper) continue;
        const char* from = "the seed constants";
        switch (sp.id) {
        case cloth::Param::AreaDensity: from = "'ClothOverMass' with w, h, u, v"; break;
        case cloth::Param::StretchWarp: from = "'SstKu' with 'SshK'"; break;
        case cloth::Param::StretchWeft: from = "'SstKv' with 'SshK'"; break;
        case cloth::Param::Shear: from = "'SshK'"; break;
        case cloth::Param::DampStretch: from = "'SstDu' and 'SstDv'"; break;
        case cloth::Param::DampShear: from = "'SshD'"; break;
        default: break;
        }
        throw ParameterError(where + ": " + from + " make a continuum " + std::string(sp.key) + " of " + format_value(x) + " " +
                             std::string(sp.unit) + ", outside the parameter table's [" + format_value(sp.lower) + ", " +
                             format_value(sp.upper) + "] " + std::string(sp.unit) +
                             (sp.id == cloth::Param::AreaDensity ? " (ClothOverMass = " + format_value(cloth_over_mass) + ")" : std::string()));
    }
}

cloth::GridSprings grid_springs(const SeedParams& s)
{
    cloth::GridSprings g;
    g.width = s.w * 0.01;
    g.height = s.h * 0.01;
    g.cells_u = s.u;
    g.cells_v = s.v;
    g.particle_mass = s.particle_mass_kg();
    g.k_u = s.sst_ku;
    g.d_u = s.sst_du;
    g.k_v = s.sst_kv;
    g.d_v = s.sst_dv;
    g.k_shear = s.ssh_k;
    g.d_shear = s.ssh_d;
    g.k_flex_u = s.sfl_ku;
    g.d_flex_u = s.sfl_du;
    g.k_flex_v = s.sfl_kv;
    g.d_flex_v = s.sfl_dv;
    return g;
}

cloth::FabricParams continuum_from_seed(const SeedParams& s)
{
    using cloth::Param;
    // Inverse of make_model's grid mapping on the seed's grid (hu, hv).
    const double hu = s.hu_m(), hv = s.hv_m();
    cloth::FabricParams p;
    p[Param::AreaDensity] = s.particle_mass_kg() / (hu * hv);
    const double ksh = (hu * hu + hv * hv) / (2 * hu * hv);
    const double G = s.ssh_k / ksh;
    p[Param::Shear] = G;
    p[Param::StretchWarp] = s.sst_ku * hu / hv + G * hu * hu / (hv * hv);
    p[Param::StretchWeft] = s.sst_kv * hv / hu + G * hv * hv / (hu * hu);
    p[Param::DampStretch] = 0.5 * (s.sst_du * hu / hv + s.sst_dv * hv / hu);
    p[Param::DampShear] = s.ssh_d / ksh;
    p[Param::DampAir] = 0;
    p[Param::Thickness] = 0;
    p[Param::Friction] = 0;
    return p;
}

namespace {

const char* const kSeedKeys[] = {"w", "h", "u", "v", "x0", "y0", "z0", "ClothOverMass", "SstKu", "SstDu", "SstKv",
                                 "SstDv", "SshK", "SshD", "SflKu", "SflDu", "SflKv", "SflDv"};

double number_field(const json& j, const std::string& key, const std::string& where)
{
    const auto it = j.find(key);
    if (it == j.end()) throw ParameterError(where + ": missing field '" + key + "'");
    if (!it->is_number()) throw ParameterError(where + ": field '" + key + "' = " + describe_json(*it) + " is not a number");
    return it->get<double>();
}

int int_field(const json& j, const std::string& key, const std::string& where)
{
    const double v = number_field(j, key, where);
    if (!std::isfinite(v) || v != std::floor(v) || v < -1e9 || v > 1e9)
        throw ParameterError(where + ": field '" + key + "' = " + format_value(v) + " is not an integer");
    return static_cast<int>(v);
}

} // namespace

bool is_seed_key(const std::string& key)
{
    if (key == "format") return true;
    for (const char* k : kSeedKeys)
        if (key == k) return true;
    return false;
}

json seed_to_json(const SeedParams& s)
{
    json j;
    j["format"] = "seed-19";
    j["w"] = s.w;
    j["h"] = s.h;
    j["u"] = s.u;
    j["v"] = s.v;
    j["x0"] = s.x0;
    j["y0"] = s.y0;
    j["z0"] = s.z0;
    j["ClothOverMass"] = s.cloth_over_mass;
    j["SstKu"] = s.sst_ku;
    j["SstDu"] = s.sst_du;
    j["SstKv"] = s.sst_kv;
    j["SstDv"] = s.sst_dv;
    j["SshK"] = s.ssh_k;
    j["SshD"] = s.ssh_d;
    j["SflKu"] = s.sfl_ku;
    j["SflDu"] = s.sfl_du;
    j["SflKv"] = s.sfl_kv;
    j["SflDv"] = s.sfl_dv;
    return j;
}

SeedParams seed_from_json(const json& j, const std::string& where)
{
    if (!j.is_object()) throw ParameterError(where + ": a seed-19 preset must be a JSON object");
    SeedParams s;
    s.w = number_field(j, "w", where);
    s.h = number_field(j, "h", where);
    s.u = int_field(j, "u", where);
    s.v = int_field(j, "v", where);
    s.x0 = number_field(j, "x0", where);
    s.y0 = number_field(j, "y0", where);
    s.z0 = number_field(j, "z0", where);
    s.cloth_over_mass = number_field(j, "ClothOverMass", where);
    s.sst_ku = number_field(j, "SstKu", where);
    s.sst_du = number_field(j, "SstDu", where);
    s.sst_kv = number_field(j, "SstKv", where);
    s.sst_dv = number_field(j, "SstDv", where);
    s.ssh_k = number_field(j, "SshK", where);
    s.ssh_d = number_field(j, "SshD", where);
    s.sfl_ku = number_field(j, "SflKu", where);
    s.sfl_du = number_field(j, "SflDu", where);
    s.sfl_kv = number_field(j, "SflKv", where);
    s.sfl_dv = number_field(j, "SflDv", where);
    s.validate(where);
    return s;
}

} // namespace drape::fabric
