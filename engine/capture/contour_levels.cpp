#include "engine/capture/contour_levels.hpp"

#include "engine/capture/pixels.hpp"
#include "engine/capture/steps.hpp"

#include <algorithm>
#include <cmath>

namespace drape::capture {

using namespace detail;

void detail::measure_contours(const record::Record& rec, const record::ContourStack& st, Measurement& out)
{
    for (std::size_t d = 0; d < st.depths.size(); ++d) {
        ContourLevel lv;
        lv.depth = st.depths[d];
        const auto& p = st.profiles[d];
        for (double r : p.r) lv.points += std::isfinite(r) ? 1 : 0;
        lv.complete = p.complete();
        lv.noise_sigma = rec.contour_sigma;
        for (int k = 0; k < p.size(); ++k) {
            const double a = p.r[static_cast<std::size_t>(k)], b = p.r[static_cast<std::size_t>((k + 1) % p.size())];
            if (std::isfinite(a) && std::isfinite(b)) lv.max_jump = std::max(lv.max_jump, std::abs(b - a));
        }
        if (lv.points < 16) {
            out.warnings.push_back("contours: depth " + fmt("%.0f", lv.depth * 1e3) + " mm has only " +
                                   std::to_string(lv.points) + " points; not fitted");
            continue;
        }
        const int max_h = std::min(120, (lv.points - 1) / 2 - 1);
        const cloth::FourierLeastSquares lsq(p, std::max(max_h, 0));
        lv.harmonics = cloth::choose_harmonics(lsq, rec.contour_sigma);
        lv.fit = lsq.fit(lv.harmonics);
        lv.residual_rms = lsq.residual_rms(lv.fit);
        // Guard: the seed interpolates each contour by its Fourier series, so the
        // series must reproduce the points to the profiler's noise. Where the
        // BIC-like stop of choose_harmonics ends above it (fine wrinkles), add
        // harmonics until the residual is down to the noise (10 % margin for
        // the sigma's own uncertainty).
        auto floor_ok = [&](double res) { return res <= 1.1 * rec.contour_sigma; };
        if (!floor_ok(lv.residual_rms)) {
            int lo = lv.harmonics, hi = lsq.max_harmonics();
            if (floor_ok(lsq.residual_rms(lsq.fit(hi)))) {
                while (hi - lo > 1) {
                    const int mid = (lo + hi) / 2;
                    if (floor_ok(lsq.residual_rms(lsq.fit(mid))))
                        hi = mid;
                    else
                        lo = mid;
                }
                lv.harmonics = hi;
                lv.fit = lsq.fit(hi);
                lv.residual_rms = lsq.residual_rms(lv.fit);
            }
        }
        lv.mean_radius = lv.fit.a0;
        if (lv.residual_rms > 1.1 * rec.contour_sigma)
            out.warnings.push_back("contours: depth " + fmt("%.0f", lv.depth * 1e3) + " mm: Fourier residual " +
                                   fmt("%.2f", lv.residual_rms * 1e3) + " mm is above the noise; the contour jumps by " +
                                   fmt("%.1f", lv.max_jump * 1e3) + " mm between neighbouring rays (an overhanging fold)");
        out.contours.push_back(lv);
    }
    if (!rec.contour_depths.empty() && rec.contour_depths.size() != st.depths.size())
        out.warnings.push_back("contours: meta.json lists " + std::to_string(rec.contour_depths.size()) +
                               " depths but the file has " + std::to_string(st.depths.size()));
    out.measured.push_back("laser contours: Fourier series per depth");
}

} // namespace drape::capture
