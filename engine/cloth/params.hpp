#pragma once
// The one parameter table. Every physical fabric parameter is declared here once
// (JSON key, unit, bounds, fit range, default, doc); preset JSON, the widget's
// property panel, the estimator's fit variables and the CLI's --set all read
// this table.
//
// Values are continuum, resolution-independent SI quantities. model.hpp turns
// them into per-element constants for a given mesh; the seed paper's 19 grid
// constants are an import/export format (engine/fabric/seed_format.hpp), not
// the core representation.
#include <array>
#include <string>
#include <string_view>

namespace drape::cloth {

/// Index of each parameter in FabricParams::values. Order is stable (it is the
/// order of the table and of exported vectors); append new ones at the end.
enum class Param : int {
    AreaDensity = 0,  ///< [kg/m^2]
    StretchWarp,      ///< [N/m] tensile stiffness along warp (u), per unit width
    StretchWeft,      ///< [N/m] tensile stiffness along weft (v)
    Shear,            ///< [N/m] in-plane shear stiffness
    BendWarp,         ///< [N*m] bending rigidity, bending about the weft axis (curving the warp)
    BendWeft,         ///< [N*m] bending rigidity curving the weft
    DampStretch,      ///< [N*s/m] viscous stretch damping per unit width
    DampShear,        ///< [N*s/m] viscous shear damping
    DampBend,         ///< [N*m*s] viscous bending damping
    DampAir,          ///< [1/s] mass-proportional (air) damping rate
    Thickness,        ///< [m] cloth thickness, used as contact offset
    Friction,         ///< [-] Coulomb friction coefficient with colliders (0 = frictionless, the seed's)
    BendStiffeningRadius, ///< [m] radius of curvature at which the bending stiffness doubles (0 = linear bending, the seed's)
    BendSofteningRadius,  ///< [m] bending that yields: moment B kappa / sqrt(1 + (rho kappa)^2), at most B / rho (0 = linear)
    BucklingLength,       ///< [m] compression limit of the membrane: at most pi^2 B / l^2 per unit width (0 = linear in compression)
    BendPeakRadius,       ///< [m] bending whose moment peaks: B kappa / (1 + (R kappa)^2), at most B / (2 R) at kappa = 1 / R, falling beyond (0 = linear)
    CompressionSlack,     ///< [1] strain of shortening the membrane takes up at 1 % of its tensile stiffness before it resists (0 = none)
    Count
};

inline constexpr int kParamCount = static_cast<int>(Param::Count);

/// Declaration of one parameter.
///
/// Keys end in their unit: a product is written without a separator and a
/// quotient after an underscore, so `bend_warp_Nm` is N*m, `stretch_warp_N_m`
/// is N/m and `damp_stretch_Ns_m` is N*s/m.
struct ParamSpec {
    Param id;
    std::string_view key;        ///< JSON key, e.g. "bend_warp_Nm"
    std::string_view legacy_key; ///< key of presets written before the unit-suffix rule ("" if unchanged); still read
    std::string_view unit;       ///< display unit, e.g. "N*m"
    double lower;                ///< smallest physically meaningful value
    double upper;                ///< largest physically meaningful value
    double default_value;
    bool log_scale;              ///< search on a log scale when fitting
    bool affects_statics;        ///< false for dampers: they do not change a rest state
    /// Range a drape test can tell apart (the fit's bounds; lies inside [lower, upper]).
    /// Equal to [lower, upper] where nothing narrower is known.
    double fit_lower;
    double fit_upper;
    std::string_view doc;
};

/// The table, in Param order.
const std::array<ParamSpec, kParamCount>& param_table();
const ParamSpec& spec(Param p);
/// Looks a parameter up by JSON key (or its legacy key); nullptr when unknown.
const ParamSpec* find_param(std::string_view key);

/// A full set of continuum fabric parameters (SI). What the parameters are
/// called and where they came from is the preset's business (engine/fabric).
struct FabricParams {
    std::array<double, kParamCount> values{};

    FabricParams(); ///< all defaults
    double& operator[](Param p) { return values[static_cast<int>(p)]; }
    double operator[](Param p) const { return values[static_cast<int>(p)]; }

    /// Throws ParameterError naming the parameter and value when a value is
    /// non-finite or outside [lower, upper]. `where` prefixes the message
    /// (e.g. the file name).
    void validate(const std::string& where = "fabric") const;
};

} // namespace drape::cloth
