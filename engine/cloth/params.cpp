#include "params.hpp"

#include "error.hpp"
#include "units.hpp"

#include <cmath>

namespace drape::cloth {

namespace {
// Ranges cover woven and knitted apparel fabrics with margin. Typical values:
// KES bending rigidity B = 0.01..0.3 gf*cm^2/cm = 1e-6..3e-5 N*m; KES shear
// rigidity G = 0.3..3 gf/cm/deg = 17..170 N/m per rad; tensile stiffness of
// woven fabrics near the origin of the load-extension curve 100..5000 N/m.
constexpr std::array<ParamSpec, kParamCount> kTable{{
    {Param::AreaDensity, "areal_density_kg_m2", "kg/m^2", 0.01, 2.0, 0.2, true, true,
     "Mass per unit area of the fabric."},
    {Param::StretchWarp, "stretch_warp_N_m", "N/m", 1.0, 1e6, 2000.0, true, true,
     "Tensile stiffness along the warp (u): force per unit width per unit strain."},
    {Param::StretchWeft, "stretch_weft_N_m", "N/m", 1.0, 1e6, 2000.0, true, true,
     "Tensile stiffness along the weft (v): force per unit width per unit strain."},
    {Param::Shear, "shear_N_m", "N/m", 0.01, 1e5, 20.0, true, true,
     "In-plane shear stiffness: shear force per unit width per radian of shear angle."},
    {Param::BendWarp, "bend_warp_N_m", "N*m", 1e-9, 1e-2, 1e-5, true, true,
     "Bending rigidity for curvature along the warp: moment per unit width per unit curvature."},
    {Param::BendWeft, "bend_weft_N_m", "N*m", 1e-9, 1e-2, 1e-5, true, true,
     "Bending rigidity for curvature along the weft: moment per unit width per unit curvature."},
    {Param::DampStretch, "damp_stretch_N_s_m", "N*s/m", 0.0, 1e3, 0.05, false, false,
     "Viscous stretch damping: force per unit width per unit strain rate."},
    {Param::DampShear, "damp_shear_N_s_m", "N*s/m", 0.0, 1e3, 0.01, false, false,
     "Viscous shear damping: force per unit width per unit shear rate."},
    {Param::DampBend, "damp_bend_N_m_s", "N*m*s", 0.0, 1.0, 1e-7, false, false,
     "Viscous bending damping: moment per unit width per unit curvature rate."},
    {Param::DampAir, "damp_air_1_s", "1/s", 0.0, 1e3, 0.5, false, false,
     "Mass-proportional damping rate (air drag, linearised)."},
    {Param::Thickness, "thickness_m", "m", 0.0, 0.01, 0.5e-3, false, true,
     "Fabric thickness; half of it is the contact offset from colliders."},
    {Param::Friction, "friction_coefficient", "-", 0.0, 2.0, 0.0, false, true,
     "Coulomb friction coefficient between cloth and colliders (0 = frictionless, as in the seed paper)."},
    {Param::BendStiffeningRadius, "bend_stiffening_radius_m", "m", 0.0, 0.05, 0.0, false, true,
     "Nonlinear (stiffening) bending: the moment per unit width is B*kappa*(1 + (r*kappa)^2), so M/kappa doubles "
     "where the radius of curvature falls to r (0 = linear bending, as in the seed paper)."},
    {Param::BendSofteningRadius, "bend_softening_radius_m", "m", 0.0, 0.05, 0.0, false, true,
     "Yielding (softening) bending: the moment per unit width is B*kappa/sqrt(1 + (rho*kappa)^2), stiff at small "
     "curvature and capped at B/rho in sharp folds, like the frictional bending of woven fabrics "
     "(0 = linear bending, as in the seed paper)."},
}};
} // namespace

const std::array<ParamSpec, kParamCount>& param_table() { return kTable; }

const ParamSpec& spec(Param p) { return kTable[static_cast<std::size_t>(p)]; }

const ParamSpec* find_param(std::string_view key)
{
    for (const auto& s : kTable)
        if (s.key == key) return &s;
    return nullptr;
}

FabricParams::FabricParams()
{
    for (const auto& s : kTable) values[static_cast<std::size_t>(s.id)] = s.default_value;
}

void FabricParams::validate(const std::string& where) const
{
    for (const auto& s : kTable) {
        const double v = values[static_cast<std::size_t>(s.id)];
        if (!std::isfinite(v))
            throw ParameterError(where + ": field '" + std::string(s.key) + "' is not a finite number");
        if (v < s.lower || v > s.upper)
            throw ParameterError(where + ": field '" + std::string(s.key) + "' = " + format_double(v) + " " +
                                 std::string(s.unit) + " is outside [" + format_double(s.lower) + ", " +
                                 format_double(s.upper) + "]");
    }
}

} // namespace drape::cloth
