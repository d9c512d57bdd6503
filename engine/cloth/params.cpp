#include "engine/cloth/params.hpp"

#include "engine/core/error.hpp"
#include "engine/core/units.hpp"

#include <cmath>

namespace drape::cloth {

namespace {
// Ranges cover woven and knitted apparel fabrics with margin. Typical values:
// KES bending rigidity B = 0.01..0.3 gf*cm^2/cm = 1e-6..3e-5 N*m; KES shear
// rigidity G = 0.3..3 gf/cm/deg = 17..170 N/m per rad; tensile stiffness of
// woven fabrics near the origin of the load-extension curve 100..5000 N/m.
//
// Fit ranges: what a 300 mm drape test can tell apart.
//  - Bending: below 1e-8 N*m a fabric drapes like a liquid sheet (D at its
//    floor); heavy stiff fabrics of set-a need up to ~1e-3 N*m along one axis.
//  - Shear: woven apparel fabrics have a KES-FB1 shear stiffness G of about
//    0.2-5 gf/(cm*deg), i.e. 11-280 N/m (1 gf/(cm*deg) = 56.2 N/m per radian;
//    Kawabata's measurements as summarised in textile handbooks); the range
//    keeps a decade of margin below (1 N/m; below it a sheet drapes like a net
//    and the static solver needs ~1000 iterations per drape) and above 1e3 N/m
//    the fold pattern no longer changes.
//  - Stiffening / softening radius: 0 (the seed's linear bending) to 30 mm;
//    beyond it the term dominates every drape curvature.
//  - Buckling length: 0 (the seed's membrane, as stiff in compression as in
//    tension) to 30 mm; at 15 mm the denim starter already drapes with 5 folds
//    instead of 8 (the membrane then carries almost no hoop compression).
//  - Tensile stiffness: 30 N/m (a loose knit) to 1e5 N/m (the drape no longer
//    changes: the sheet is inextensible at drape loads).
constexpr std::array<ParamSpec, kParamCount> kTable{{
    {Param::AreaDensity, "areal_density_kg_m2", "", "kg/m^2", 0.01, 2.0, 0.2, true, true, 0.01, 2.0,
     "Mass per unit area of the fabric."},
    {Param::StretchWarp, "stretch_warp_N_m", "", "N/m", 1.0, 1e6, 2000.0, true, true, 30.0, 1e5,
     "Tensile stiffness along the warp (u): force per unit width per unit strain."},
    {Param::StretchWeft, "stretch_weft_N_m", "", "N/m", 1.0, 1e6, 2000.0, true, true, 30.0, 1e5,
     "Tensile stiffness along the weft (v): force per unit width per unit strain."},
    {Param::Shear, "shear_N_m", "", "N/m", 0.01, 1e5, 20.0, true, true, 1.0, 1e3,
     "In-plane shear stiffness: shear force per unit width per radian of shear angle."},
    {Param::BendWarp, "bend_warp_Nm", "bend_warp_N_m", "N*m", 1e-9, 1e-2, 1e-5, true, true, 1e-8, 1e-2,
     "Bending rigidity for curvature along the warp: moment per unit width per unit curvature."},
    {Param::BendWeft, "bend_weft_Nm", "bend_weft_N_m", "N*m", 1e-9, 1e-2, 1e-5, true, true, 1e-8, 1e-2,
     "Bending rigidity for curvature along the weft: moment per unit width per unit curvature."},
    {Param::DampStretch, "damp_stretch_Ns_m", "damp_stretch_N_s_m", "N*s/m", 0.0, 1e3, 0.05, false, false, 0.0, 1e3,
     "Viscous stretch damping: force per unit width per unit strain rate."},
    {Param::DampShear, "damp_shear_Ns_m", "damp_shear_N_s_m", "N*s/m", 0.0, 1e3, 0.01, false, false, 0.0, 1e3,
     "Viscous shear damping: force per unit width per unit shear rate."},
    {Param::DampBend, "damp_bend_Nms", "damp_bend_N_m_s", "N*m*s", 0.0, 1.0, 1e-7, false, false, 0.0, 1.0,
     "Viscous bending damping: moment per unit width per unit curvature rate."},
    {Param::DampAir, "damp_air_1_s", "", "1/s", 0.0, 1e3, 0.5, false, false, 0.0, 1e3,
     "Mass-proportional damping rate (air drag, linearised)."},
    {Param::Thickness, "thickness_m", "", "m", 0.0, 0.01, 0.5e-3, false, true, 0.0, 0.01,
     "Fabric thickness; half of it is the contact offset from colliders."},
    {Param::Friction, "friction_coefficient", "", "-", 0.0, 2.0, 0.0, false, true, 0.0, 2.0,
     "Coulomb friction coefficient between cloth and colliders (0 = frictionless, as in the seed paper)."},
    {Param::BendStiffeningRadius, "bend_stiffening_radius_m", "", "m", 0.0, 0.05, 0.0, false, true, 0.0, 0.03,
     "Nonlinear (stiffening) bending: the moment per unit width is B*kappa*(1 + (r*kappa)^2), so M/kappa doubles "
     "where the radius of curvature falls to r (0 = linear bending, as in the seed paper)."},
    {Param::BendSofteningRadius, "bend_softening_radius_m", "", "m", 0.0, 0.05, 0.0, false, true, 0.0, 0.03,
     "Yielding (softening) bending: the moment per unit width is B*kappa/sqrt(1 + (rho*kappa)^2), stiff at small "
     "curvature and capped at B/rho in sharp folds, like the frictional bending of woven fabrics "
     "(0 = linear bending, as in the seed paper)."},
    {Param::BucklingLength, "buckling_length_m", "", "m", 0.0, 0.1, 0.0, false, true, 0.0, 0.03,
     "Compression limit of the membrane: in compression the fabric carries at most the Euler stress pi^2*B/l^2 per "
     "unit width (B its bending rigidity along the compressed direction, l this length) and shortens beyond it by "
     "wrinkling on a scale the mesh does not show, as woven fabric buckles at a small fraction of its tensile "
     "stiffness. A material length, the same on every mesh (0 = as stiff in compression as in tension, as in the "
     "seed paper)."},
    {Param::BendPeakRadius, "bend_peak_radius_m", "", "m", 0.0, 0.05, 0.0, false, true, 0.0, 0.03,
     "Bending whose moment peaks and then falls: the moment per unit width is B*kappa/(1 + (R*kappa)^2), at most "
     "B/(2R) where the radius of curvature is R, where the tangent stiffness is 0 (cantilever measurements of real "
     "fabrics put it near 5 mm), and falling in sharper bends, which hinge. Not with bend_softening_radius_m "
     "(0 = linear bending, as in the seed paper)."},
    {Param::CompressionSlack, "compression_slack", "", "-", 0.0, 0.2, 0.0, false, true, 0.0, 0.05,
     "Slack in compression: the strain by which the membrane (warp, weft and the shear diagonals) shortens at 1 % "
     "of its tensile stiffness before it resists as in tension, the crimp of woven yarns taking it up; beyond it the "
     "buckling length's limit applies as before (0 = as stiff in compression as in tension, as in the seed paper)."},
}};

constexpr bool table_is_consistent()
{
    for (std::size_t i = 0; i < kTable.size(); ++i) {
        const auto& s = kTable[i];
        if (static_cast<std::size_t>(s.id) != i) return false;
        if (!(s.lower <= s.fit_lower && s.fit_lower < s.fit_upper && s.fit_upper <= s.upper)) return false;
        if (!(s.lower <= s.default_value && s.default_value <= s.upper)) return false;
        if (s.log_scale && !(s.fit_lower > 0)) return false;
    }
    return true;
}
static_assert(table_is_consistent(), "parameter table: ids in order, defaults and fit ranges inside the bounds");
} // namespace

const std::array<ParamSpec, kParamCount>& param_table() { return kTable; }

const ParamSpec& spec(Param p) { return kTable[static_cast<std::size_t>(p)]; }

const ParamSpec* find_param(std::string_view key)
{
    for (const auto& s : kTable)
        if (s.key == key || (!s.legacy_key.empty() && s.legacy_key == key)) return &s;
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
            throw ParameterError(where + ": field '" + std::string(s.key) + "' = " + format_value(v) + " " +
                                 std::string(s.unit) + " is outside [" + format_value(s.lower) + ", " +
                                 format_value(s.upper) + "]");
    }
    if (values[static_cast<std::size_t>(Param::BendSofteningRadius)] > 0 && values[static_cast<std::size_t>(Param::BendPeakRadius)] > 0)
        throw ParameterError(where + ": fields 'bend_softening_radius_m' and 'bend_peak_radius_m' are two laws of the bending's nonlinearity: "
                             "set one (the other 0)");
}

} // namespace drape::cloth
