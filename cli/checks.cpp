#include "cli/checks.hpp"

#include "engine/core/error.hpp"
#include "engine/core/units.hpp"

#include <cmath>
#include <cstdio>

namespace drape::cli {

namespace {
std::string outside(const char* what, double v, double lo, double hi, const char* unit)
{
    if (std::isfinite(v) && v >= lo && v <= hi) return {};
    return std::string(what) + " = " + format_value(v) + " " + unit + " is outside [" + format_value(lo) + ", " + format_value(hi) +
           "] " + unit;
}
} // namespace

std::string unphysical(const cloth::DrapeResult& r, const cloth::DrapeSetup& s)
{
    const double R1 = 0.5 * s.sample_diameter;
    // The floor is at -pedestal height (a collider; 10 mm for its contact
    // thickness); nothing hangs higher than a specimen radius above the disc.
    const double z_lo = -(s.pedestal_height + 0.01), z_hi = R1;
    for (const std::string& why :
         {outside("D", r.metrics.drape_coefficient_percent, 0, 100, "%"),
          outside("node count", r.metrics.node_count, 0, 100, ""),
          outside("lowest hem height", r.hem.min_z * 1e3, z_lo * 1e3, z_hi * 1e3, "mm"),
          outside("highest hem height", r.hem.max_z * 1e3, z_lo * 1e3, z_hi * 1e3, "mm"),
          outside("largest shadow radius", r.metrics.max_radius_m * 1e3, 0, 1.5e3 * R1, "mm")})
        if (!why.empty()) return why;
    return {};
}

bool check_drape_result(const cloth::DrapeResult& r, const cloth::DrapeSetup& setup)
{
    const std::string why = unphysical(r, setup);
    if (why.empty()) return true;
    if (r.status.converged())
        throw Error("the drape's " + why + ": not a physical result, not printed");
    std::fprintf(stderr, "the solver did not reach rest (%s), and the last state is not physical (%s): no metrics printed\n",
                 r.status.message.empty() ? "no message" : r.status.message.c_str(), why.c_str());
    return false;
}

} // namespace drape::cli
