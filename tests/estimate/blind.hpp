#pragma once
// The blind suite's records (issue 20): synthetic drapes made by the engine with
// one undeclared effect switched on, measured like the lab, and the baseline fit
// of them. Shared by tst_est_blind (unit) and tst_est_blind_slow.
#include "engine/estimate/fit.hpp"
#include "synthetic.hpp"

#include <cmath>
#include <string>

namespace drape::estimate::test::blind {

using cloth::Param;


inline constexpr int kGrid = 25;

inline cloth::FabricParams truth()
{
    cloth::FabricParams p = default_fit_start(); // the fit's held compression limit (7.5 mm)
    p[Param::BendWarp] = 1.5e-5;
    p[Param::BendWeft] = 8.0e-6;
    p[Param::Shear] = 20;
    p[Param::AreaDensity] = 0.2;
    return p;
}

/// The cut `p` seen by a profiler whose axis is (sx, sy) off the pedestal's: the
/// curve itself moved and sampled again on the profiler's rays (not the first-order
/// r += s cos(theta - phi), which is exact for a circle only: a folded cut's
/// flanks move along the rays too).
inline cloth::RadialProfile shifted(const cloth::RadialProfile& p, double sx, double sy)
{
    cloth::Polygon2 poly = cloth::polygon_from_profile(p);
    for (auto& v : poly) v += Eigen::Vector2d(sx, sy);
    return cloth::radial_profile(poly, p.size());
}

/// A record of `p` with the effect `effect` at `strength` injected (the record
/// does not declare it), noise seed from `seed`.
inline MeasuredDrape injected(const std::string& effect, double strength, std::uint64_t seed)
{
    cloth::FabricParams p = truth();
    cloth::DrapeSetup s = drape_setup(0.30, 0.15, kGrid, seed);
    cloth::ModelOptions mo;
    if (effect == "buckling") p[Param::BucklingLength] = strength;               // [m]
    if (effect == "bending_stiffening") p[Param::BendStiffeningRadius] = strength; // [m]
    if (effect == "disc_grip") s.disc_grip = true;
    if (effect == "contact_resolution") mo.edge_contact = false;
    if (effect == "self_contact") mo.self_collision = true;
    const double direction = 1.3 * static_cast<double>(seed); // a phase per record
    if (effect == "specimen_off_centre") s.specimen_offset = strength * Eigen::Vector2d(std::cos(direction), std::sin(direction)); // [m]
    if (effect == "specimen_weight_gradient") s.density_gradient = strength * Eigen::Vector2d(std::cos(direction), std::sin(direction));
    if (effect == "disc_diameter") s.disc_diameter += strength; // [m] the pedestal wider than the record declares (not a candidate: docs/model-discrepancy.md)
    if (effect == "tensile_anisotropy") { // warp stiffer, weft softer by the factor (1 + strength)
        p[Param::StretchWarp] *= 1 + strength;
        p[Param::StretchWeft] /= 1 + strength;
    }
    MeasuredDrape rec = synthesize_record(cloth::simulate_drape(p, s, {}, mo), s, p, 0.3e-3, seed + 100, effect);
    if (effect == "profiler_off_axis") {
        // The profiler's axis `strength` metres off the pedestal's (towards the
        // record's direction): every cut moved by that, sampled again.
        for (auto& c : rec.contours) c.profile = shifted(c.profile, strength * std::cos(direction), strength * std::sin(direction));
    }
    if (effect == "profiler_tilt") {
        // The profiler's axis tilted by `strength` radians: the cut at depth d
        // is d tan(strength) off the pedestal's axis.
        for (auto& c : rec.contours) {
            const double sh = c.depth_m * std::tan(strength);
            c.profile = shifted(c.profile, sh * std::cos(direction), sh * std::sin(direction));
        }
    }
    if (effect == "camera_scale") {
        // The top photo's scale off by `strength`: the shadow's area by (1 + s)^2.
        const double a0 = std::pow(rec.sample_diameter / 2, 2), ad = std::pow(rec.disc_diameter / 2, 2);
        const double as = ad + rec.drape_coefficient_percent / 100 * (a0 - ad);
        rec.drape_coefficient_percent = 100 * (as * (1 + strength) * (1 + strength) - ad) / (a0 - ad);
    }
    if (effect == "declared_weight") rec.areal_density *= 1 + strength; // the lab declares a wrong weight
    if (effect == "disc_diameter") {
        // The lab declares the nominal disc and computes D from the shadow's area with it.
        const double a0 = std::pow(rec.sample_diameter / 2, 2), at = std::pow(rec.disc_diameter / 2, 2);
        const double as = at + rec.drape_coefficient_percent / 100 * (a0 - at);
        rec.disc_diameter -= strength;
        const double ad = std::pow(rec.disc_diameter / 2, 2);
        rec.drape_coefficient_percent = 100 * (as - ad) / (a0 - ad);
    }
    return rec;
}

inline FitResult fit(const MeasuredDrape& rec)
{
    FitOptions o;
    o.grid = kGrid;
    o.start = default_fit_start();
    return fit_fabric({rec}, o);
}

} // namespace drape::estimate::test::blind
