#pragma once
// The one parameter table. Every physical fabric parameter is declared here once
// (name, unit, bounds, default, doc); JSON I/O, the widget's property panel, the
// estimator's bounds and the CLI all read this table.
//
// Values are continuum, resolution-independent SI quantities. model.hpp turns
// them into per-spring constants for a given mesh; the seed paper's 19 grid
// constants are an import/export format (seed_format.hpp), not the core
// representation.
#include <array>
#include <string>
#include <string_view>
#include <vector>

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
    Count
};

inline constexpr int kParamCount = static_cast<int>(Param::Count);

/// Declaration of one parameter.
struct ParamSpec {
    Param id;
    std::string_view key;   ///< JSON key (unit suffixed), e.g. "bend_warp_N_m"
    std::string_view unit;  ///< display unit, e.g. "N*m"
    double lower;           ///< smallest physically meaningful value
    double upper;           ///< largest physically meaningful value
    double default_value;
    bool log_scale;         ///< search on a log scale when fitting
    bool affects_statics;   ///< false for dampers: they do not change a rest state
    std::string_view doc;
};

/// The table, in Param order.
const std::array<ParamSpec, kParamCount>& param_table();
const ParamSpec& spec(Param p);
/// Looks a parameter up by JSON key; returns nullptr when unknown.
const ParamSpec* find_param(std::string_view key);

/// A full set of continuum fabric parameters (SI), with a name and free-form
/// provenance kept as JSON text.
struct FabricParams {
    std::array<double, kParamCount> values{};
    std::string name = "unnamed";

    FabricParams(); ///< all defaults
    double& operator[](Param p) { return values[static_cast<int>(p)]; }
    double operator[](Param p) const { return values[static_cast<int>(p)]; }

    /// Throws ParameterError naming the parameter and value when a value is
    /// non-finite or outside [lower, upper]. `where` prefixes the message
    /// (e.g. the file name).
    void validate(const std::string& where = "fabric") const;
};

} // namespace drape::cloth
