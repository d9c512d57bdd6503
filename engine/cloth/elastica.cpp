#include "engine/cloth/elastica.hpp"

#include "engine/core/error.hpp"
#include "engine/core/units.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace drape::cloth {

ElasticaTip heavy_elastica(double lambda, int segments)
{
    if (!std::isfinite(lambda) || lambda < 0)
        throw ParameterError("heavy elastica: lambda = w L^3 / B = " + format_double(lambda) + " must be a finite number >= 0");
    if (segments < 4) throw ParameterError("heavy elastica: " + std::to_string(segments) + " segments; at least 4");
    const int n = segments;
    const double h = 1.0 / n;
    // Segment i (1..n) at angle t[i-1] below the horizontal; energy in units of
    // B / L: bending n/2 sum (t_i - t_(i-1))^2 between neighbouring segments'
    // centres, n t_1^2 from the clamp (t_0 = 0) to the first one's, half a
    // segment away; weight
    // -lambda h^2 sum (n - i + 1/2) sin t_i (a segment lowers every later one by
    // h sin t_i and its own centre by half that).
    std::vector<double> load(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) load[static_cast<std::size_t>(i)] = lambda * h * h * (n - i - 0.5);
    auto energy = [&](const std::vector<double>& t) {
        double e = 0, prev = 0;
        for (int i = 0; i < n; ++i) {
            const double ti = t[static_cast<std::size_t>(i)];
            e += (i == 0 ? 1.0 : 0.5) * n * (ti - prev) * (ti - prev) - load[static_cast<std::size_t>(i)] * std::sin(ti);
            prev = ti;
        }
        return e;
    };
    // Start from the small-deflection beam's slope, capped below plumb.
    std::vector<double> t(static_cast<std::size_t>(n)), g(t.size()), a(t.size()), c(t.size()), d(t.size()), step(t.size()),
        trial(t.size());
    for (int i = 0; i < n; ++i) {
        const double s = (i + 1) * h;
        t[static_cast<std::size_t>(i)] = std::min(1.4, lambda * (s - s * s + s * s * s / 3) / 2);
    }
    double e = energy(t);
    ElasticaTip tip;
    for (int it = 0; it < 200; ++it) {
        double gmax = 0;
        for (int i = 0; i < n; ++i) {
            const auto k = static_cast<std::size_t>(i);
            const double left = i > 0 ? t[k] - t[k - 1] : 2 * t[k];
            const double right = i + 1 < n ? t[k] - t[k + 1] : 0.0;
            g[k] = n * (left + right) - load[k] * std::cos(t[k]);
            // The bending's tridiagonal Hessian and the weight's diagonal one,
            // kept positive (a convex model of the step).
            a[k] = n * ((i > 0 ? 1.0 : 2.0) + (i + 1 < n ? 1.0 : 0.0)) + std::max(load[k] * std::sin(t[k]), 0.0);
            gmax = std::max(gmax, std::abs(g[k]));
        }
        if (gmax < 1e-12 * std::max(1.0, lambda)) {
            tip.converged = true;
            break;
        }
        // Thomas algorithm: H step = -g, off-diagonals -n.
        c[0] = -n / a[0];
        d[0] = -g[0] / a[0];
        for (std::size_t k = 1; k < t.size(); ++k) {
            const double m = a[k] + n * c[k - 1];
            c[k] = -n / m;
            d[k] = (-g[k] + n * d[k - 1]) / m;
        }
        step.back() = d.back();
        for (std::size_t k = t.size() - 1; k-- > 0;) step[k] = d[k] - c[k] * step[k + 1];
        double smax = 0;
        for (double v : step) smax = std::max(smax, std::abs(v));
        if (smax < 1e-8) { // a Newton step of 1e-8 rad: at rest (the energy resolves no finer)
            tip.converged = true;
            break;
        }
        double alpha = 1, et = e;
        for (; alpha > 1e-10; alpha *= 0.5) {
            for (std::size_t k = 0; k < t.size(); ++k) trial[k] = std::clamp(t[k] + alpha * step[k], -0.5, std::numbers::pi / 2 + 0.5);
            et = energy(trial);
            if (et <= e) break;
        }
        if (!(alpha > 1e-10)) {
            tip.converged = smax < 1e-6; // the energy no longer resolves so small a step [rad]
            break;
        }
        t.swap(trial);
        e = et;
    }
    tip.reach = 0;
    tip.drop = 0;
    for (double ti : t) tip.reach += h * std::cos(ti), tip.drop += h * std::sin(ti);
    return tip;
}

namespace {

void check_setup(const char* what, double sample_diameter, double disc_diameter, double areal_density, double gravity)
{
    auto positive = [&](const char* name, double v) {
        if (!std::isfinite(v) || !(v > 0))
            throw ParameterError(std::string(what) + ": " + name + " = " + format_double(v) + " must be a positive number");
    };
    positive("sample diameter", sample_diameter);
    positive("disc diameter", disc_diameter);
    positive("areal density", areal_density);
    positive("gravity", gravity);
    if (!(disc_diameter < sample_diameter))
        throw ParameterError(std::string(what) + ": disc diameter " + format_double(disc_diameter) + " m is not smaller than the sample's " +
                             format_double(sample_diameter) + " m");
}

} // namespace

double free_strip_drape_coefficient(double sample_diameter, double disc_diameter, double areal_density, double bending, double gravity)
{
    check_setup("free-strip drape", sample_diameter, disc_diameter, areal_density, gravity);
    if (!std::isfinite(bending) || !(bending > 0))
        throw ParameterError("free-strip drape: bending = " + format_double(bending) + " N*m must be a positive number");
    const double R1 = sample_diameter / 2, R2 = disc_diameter / 2, L = R1 - R2;
    const ElasticaTip tip = heavy_elastica(areal_density * gravity * L * L * L / bending);
    const double r = R2 + tip.reach * L;
    return 100.0 * (r * r - R2 * R2) / (R1 * R1 - R2 * R2);
}

double free_strip_bending_bound(double sample_diameter, double disc_diameter, double areal_density, double dc_percent, double gravity)
{
    check_setup("free-strip bound", sample_diameter, disc_diameter, areal_density, gravity);
    if (!std::isfinite(dc_percent) || !(dc_percent > 0) || !(dc_percent < 100))
        throw ParameterError("free-strip bound: D = " + format_double(dc_percent) + " % must lie in (0, 100)");
    // D of the strips rises with B: bisection on log B over twelve decades.
    double lo = std::log(1e-12), hi = std::log(1e0);
    for (int i = 0; i < 60; ++i) {
        const double mid = 0.5 * (lo + hi);
        (free_strip_drape_coefficient(sample_diameter, disc_diameter, areal_density, std::exp(mid), gravity) > dc_percent ? hi : lo) = mid;
    }
    return std::exp(0.5 * (lo + hi));
}

} // namespace drape::cloth
