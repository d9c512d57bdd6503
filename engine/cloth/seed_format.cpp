#include "seed_format.hpp"

#include "error.hpp"
#include "units.hpp"

#include <cmath>
#include <cstdlib>

namespace drape::cloth {

double SeedParams::hu_m() const { return w * 0.01 / u; }
double SeedParams::hv_m() const { return h * 0.01 / v; }
double SeedParams::particle_mass_kg() const { return kSeedMassUnitKg / cloth_over_mass; }

void SeedParams::validate(const std::string& where) const
{
    auto positive = [&](const char* name, double x) {
        if (!std::isfinite(x) || !(x > 0))
            throw ParameterError(where + ": field '" + name + "' = " + format_double(x) + " must be a positive number");
    };
    auto nonneg = [&](const char* name, double x) {
        if (!std::isfinite(x) || x < 0)
            throw ParameterError(where + ": field '" + name + "' = " + format_double(x) + " must be a non-negative number");
    };
    positive("w", w);
    positive("h", h);
    if (u < 4 || u > 2000) throw ParameterError(where + ": field 'u' = " + std::to_string(u) + " must be in [4, 2000]");
    if (v < 4 || v > 2000) throw ParameterError(where + ": field 'v' = " + std::to_string(v) + " must be in [4, 2000]");
    for (auto [n, x] : {std::pair{"x0", x0}, {"y0", y0}, {"z0", z0}})
        if (!std::isfinite(x)) throw ParameterError(where + ": field '" + n + "' is not a finite number");
    positive("ClothOverMass", cloth_over_mass);
    positive("SstKu", sst_ku);
    positive("SstKv", sst_kv);
    nonneg("SshK", ssh_k);
    nonneg("SflKu", sfl_ku);
    nonneg("SflKv", sfl_kv);
    nonneg("SstDu", sst_du);
    nonneg("SstDv", sst_dv);
    nonneg("SshD", ssh_d);
    nonneg("SflDu", sfl_du);
    nonneg("SflDv", sfl_dv);
}

FabricParams continuum_from_seed(const SeedParams& s)
{
    // Inverse of make_model's grid mapping on the seed's grid (hu, hv).
    const double hu = s.hu_m(), hv = s.hv_m();
    FabricParams p;
    p.name = "from seed-19";
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

} // namespace drape::cloth
