#pragma once
// One-dimensional root search for the estimator's monotonic responses (drape
// coefficient against log bending or log flexion stiffness).
#include <algorithm>
#include <cmath>
#include <utility>

namespace drape::estimate {

/// Regula falsi with the Illinois modification on a bracket with f(lo) = flo < 0
/// < fhi = f(hi). Calls f at most `max_evals` times and stops once |f| <= tol.
/// Each new point stays 5 % of the bracket away from its ends (f is noisy: fold
/// patterns). Returns the evaluated point with the smallest |f| and its value
/// ({NaN, inf} when nothing was evaluated).
template <class F>
std::pair<double, double> illinois_root(F&& f, double lo, double flo, double hi, double fhi, double tol, int max_evals)
{
    std::pair<double, double> best{std::nan(""), HUGE_VAL};
    int side = 0;
    for (int it = 0; it < max_evals && std::abs(best.second) > tol; ++it) {
        double c = lo - flo * (hi - lo) / (fhi - flo);
        c = std::clamp(c, lo + 0.05 * (hi - lo), hi - 0.05 * (hi - lo));
        const double e = f(c);
        if (std::abs(e) < std::abs(best.second)) best = {c, e};
        if (e > 0) {
            hi = c, fhi = e;
            if (side == 1) flo *= 0.5;
            side = 1;
        } else {
            lo = c, flo = e;
            if (side == -1) fhi *= 0.5;
            side = -1;
        }
    }
    return best;
}

} // namespace drape::estimate
