#include "engine/cloth/metrics.hpp"

#include "engine/core/error.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace drape::cloth {

namespace {
constexpr double kTwoPi = 2.0 * std::numbers::pi;
const double kNaN = std::numeric_limits<double>::quiet_NaN();

double cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

/// Calls f(k, cos k theta, sin k theta) for k = 1..K, the terms by rotation
/// instead of a sincos each (the error grows like k eps: 1e-14 at k = 120).
template <class F>
void for_each_harmonic(double theta, int K, F&& f)
{
    const double c1 = std::cos(theta), s1 = std::sin(theta);
    double ck = 1.0, sk = 0.0;
    for (int k = 1; k <= K; ++k) {
        const double cn = ck * c1 - sk * s1;
        sk = sk * c1 + ck * s1;
        ck = cn;
        f(k, ck, sk);
    }
}

/// For the segment p-q, updates r[k] = max(r[k], distance along ray k to the
/// crossing) for every ray the segment crosses. Rays are theta_k = 2 pi k / N
/// from the origin. Works on the angular span of the segment, so the cost is
/// proportional to the rays it actually crosses.
void accumulate_segment(const Eigen::Vector2d& p, const Eigen::Vector2d& q, std::vector<double>& r)
{
    const int n = static_cast<int>(r.size());
    const double step = kTwoPi / n;
    const Eigen::Vector2d e = q - p;
    const double ap = std::atan2(p.y(), p.x());
    double span = std::atan2(q.y(), q.x()) - ap;
    if (span > std::numbers::pi) span -= kTwoPi;
    if (span < -std::numbers::pi) span += kTwoPi;
    double a0 = span >= 0 ? ap : ap + span;
    const double a1 = a0 + std::abs(span);
    const int k0 = static_cast<int>(std::floor(a0 / step)) - 1;
    const int k1 = static_cast<int>(std::ceil(a1 / step)) + 1;
    for (int kk = k0; kk <= k1; ++kk) {
        const double th = kk * step;
        const Eigen::Vector2d d(std::cos(th), std::sin(th));
        const double den = cross2(d, e);
        if (std::abs(den) < 1e-300) continue;
        const double s = cross2(p, e) / den;
        const double t = cross2(p, d) / den;
        if (s <= 0 || t < -1e-12 || t > 1 + 1e-12) continue;
        const int k = ((kk % n) + n) % n;
        double& rk = r[static_cast<std::size_t>(k)];
        if (std::isnan(rk) || s > rk) rk = s;
    }
}
} // namespace

double RadialProfile::theta(int k) const { return kTwoPi * k / static_cast<double>(r.size()); }

bool RadialProfile::complete() const
{
    return !r.empty() && std::none_of(r.begin(), r.end(), [](double x) { return std::isnan(x); });
}

RadialProfile radial_profile(const Polygon2& poly, int samples)
{
    if (samples < 8) throw ParameterError("radial_profile: samples = " + std::to_string(samples) + " < 8");
    RadialProfile out;
    out.r.assign(static_cast<std::size_t>(samples), kNaN);
    const std::size_t n = poly.size();
    for (std::size_t i = 0; i < n; ++i) accumulate_segment(poly[i], poly[(i + 1) % n], out.r);
    return out;
}

Polygon2 polygon_from_profile(const RadialProfile& p)
{
    Polygon2 poly;
    poly.reserve(p.r.size());
    for (int k = 0; k < p.size(); ++k) {
        const double r = p.r[static_cast<std::size_t>(k)];
        if (std::isnan(r)) continue;
        poly.emplace_back(r * std::cos(p.theta(k)), r * std::sin(p.theta(k)));
    }
    return poly;
}

double FourierSeries::magnitude(int k) const
{
    if (k < 1 || k > harmonics()) return 0.0;
    return std::hypot(a[static_cast<std::size_t>(k - 1)], b[static_cast<std::size_t>(k - 1)]);
}

double FourierSeries::evaluate(double theta) const
{
    // (find_nodes and the residuals evaluate 24-120 harmonics at 720 angles per contour.)
    double s = a0;
    for_each_harmonic(theta, harmonics(), [&](int k, double ck, double sk) {
        s += a[static_cast<std::size_t>(k - 1)] * ck + b[static_cast<std::size_t>(k - 1)] * sk;
    });
    return s;
}

FourierLeastSquares::FourierLeastSquares(const RadialProfile& p, int max_harmonics)
{
    if (max_harmonics < 0)
        throw ParameterError("fourier_fit: harmonics = " + std::to_string(max_harmonics) + " < 0");
    std::vector<int> rows;
    for (int k = 0; k < p.size(); ++k)
        if (!std::isnan(p.r[static_cast<std::size_t>(k)])) rows.push_back(k);
    const int m = static_cast<int>(rows.size());
    // Never fit more coefficients than samples allow (keep the system overdetermined).
    max_harmonics_ = std::min(max_harmonics, std::max(0, (m - 1) / 2 - 1));
    const int cols = 2 * max_harmonics_ + 1;
    basis_.resize(m, cols);
    y_.resize(m);
    for (int i = 0; i < m; ++i) {
        basis_(i, 0) = 1.0;
        for_each_harmonic(p.theta(rows[static_cast<std::size_t>(i)]), max_harmonics_, [&](int k, double ck, double sk) {
            basis_(i, 2 * k - 1) = ck;
            basis_(i, 2 * k) = sk;
        });
        y_(i) = p.r[static_cast<std::size_t>(rows[static_cast<std::size_t>(i)])];
    }
    normal_ = basis_.transpose() * basis_;
    rhs_ = basis_.transpose() * y_;
}

FourierSeries FourierLeastSquares::fit(int harmonics) const
{
    if (harmonics < 0) throw ParameterError("fourier_fit: harmonics = " + std::to_string(harmonics) + " < 0");
    harmonics = std::min(harmonics, max_harmonics_);
    FourierSeries s;
    s.a.assign(static_cast<std::size_t>(harmonics), 0.0);
    s.b.assign(static_cast<std::size_t>(harmonics), 0.0);
    if (y_.size() == 0) {
        s.a0 = kNaN;
        return s;
    }
    const int cols = 2 * harmonics + 1;
    const Eigen::VectorXd c = normal_.topLeftCorner(cols, cols).ldlt().solve(rhs_.head(cols));
    s.a0 = c(0);
    for (int k = 1; k <= harmonics; ++k) {
        s.a[static_cast<std::size_t>(k - 1)] = c(2 * k - 1);
        s.b[static_cast<std::size_t>(k - 1)] = c(2 * k);
    }
    return s;
}

double FourierLeastSquares::residual_rms(const FourierSeries& s) const
{
    const int m = static_cast<int>(y_.size());
    if (m == 0) return kNaN;
    if (s.harmonics() > max_harmonics_)
        throw ParameterError("FourierLeastSquares::residual_rms: series of " + std::to_string(s.harmonics()) +
                             " harmonics > " + std::to_string(max_harmonics_));
    const int cols = 2 * s.harmonics() + 1;
    Eigen::VectorXd c(cols);
    c(0) = s.a0;
    for (int k = 1; k <= s.harmonics(); ++k) {
        c(2 * k - 1) = s.a[static_cast<std::size_t>(k - 1)];
        c(2 * k) = s.b[static_cast<std::size_t>(k - 1)];
    }
    const Eigen::VectorXd res = y_ - basis_.leftCols(cols) * c;
    return std::sqrt(res.squaredNorm() / m);
}

FourierSeries fourier_fit(const RadialProfile& p, int harmonics)
{
    return FourierLeastSquares(p, harmonics).fit(harmonics);
}

double fourier_residual_rms(const RadialProfile& p, const FourierSeries& s)
{
    double ss = 0;
    int m = 0;
    for (int k = 0; k < p.size(); ++k) {
        const double r = p.r[static_cast<std::size_t>(k)];
        if (std::isnan(r)) continue;
        const double d = r - s.evaluate(p.theta(k));
        ss += d * d;
        ++m;
    }
    return m ? std::sqrt(ss / m) : kNaN;
}

int choose_harmonics(const RadialProfile& p, double noise_sigma, int max_harmonics)
{
    int m = 0;
    for (double r : p.r) m += !std::isnan(r);
    if (m < 8) return 0;
    if (max_harmonics < 0) max_harmonics = m / 3;
    return choose_harmonics(FourierLeastSquares(p, std::max(max_harmonics, 0)), noise_sigma);
}

int choose_harmonics(const FourierLeastSquares& lsq, double noise_sigma)
{
    const int m = lsq.hit_rays();
    if (m < 8) return 0;
    // Smallest K whose residual variance is consistent with the noise: the
    // unbiased variance estimate RSS/(m - 2K - 1) within two standard errors of
    // sigma^2 (chi-square with m - 2K - 1 degrees of freedom). Falls back to the
    // BIC minimum when the noise is not reached (e.g. sigma under-declared).
    int best_bic_k = 0;
    double best_bic = std::numeric_limits<double>::infinity();
    for (int K = 0; K <= lsq.max_harmonics(); ++K) {
        const double rms = lsq.residual_rms(lsq.fit(K));
        const double rss = rms * rms * m;
        const int dof = m - (2 * K + 1);
        if (dof <= 0) break;
        if (noise_sigma > 0) {
            const double var = rss / dof;
            const double limit = noise_sigma * noise_sigma * (1.0 + 2.0 * std::sqrt(2.0 / dof));
            if (var <= limit) return K;
        }
        const double bic = m * std::log(std::max(rss / m, 1e-30)) + (2 * K + 1) * std::log(static_cast<double>(m));
        if (bic < best_bic) {
            best_bic = bic;
            best_bic_k = K;
        }
    }
    return best_bic_k;
}

void find_nodes(const RadialProfile& p, const MetricOptions& opt, DrapeMetrics& out)
{
    out.node_count = 0;
    out.node_angles_rad.clear();
    out.node_amplitudes_m.clear();
    const int n = std::max(opt.samples, 64);
    std::vector<double> r(static_cast<std::size_t>(n));
    for (int k = 0; k < n; ++k) r[static_cast<std::size_t>(k)] = out.fourier.evaluate(kTwoPi * k / n);
    const auto [mn, mx] = std::minmax_element(r.begin(), r.end());
    const double threshold = std::max(opt.min_prominence_m, opt.relative_prominence * (*mx - *mn));
    (void)p;
    // Alternating list of cyclic extrema (index, is_max), then persistence
    // simplification: repeatedly drop the weakest crest (crest minus the higher
    // of its two neighbouring troughs) with its higher trough until every crest
    // stands out by `threshold`.
    struct Ext {
        int k;
        bool max;
    };
    std::vector<Ext> ext;
    for (int k = 0; k < n; ++k) {
        const double prev = r[static_cast<std::size_t>((k + n - 1) % n)];
        const double cur = r[static_cast<std::size_t>(k)];
        double nxt = r[static_cast<std::size_t>((k + 1) % n)];
        // Plateaus: compare with the next different value.
        for (int j = 2; j < n && nxt == cur; ++j) nxt = r[static_cast<std::size_t>((k + j) % n)];
        if (cur > prev && cur >= nxt && cur != nxt) ext.push_back({k, true});
        else if (cur < prev && cur <= nxt && cur != nxt) ext.push_back({k, false});
    }
    auto val = [&](const Ext& e) { return r[static_cast<std::size_t>(e.k)]; };
    while (ext.size() >= 4) {
        const int m = static_cast<int>(ext.size());
        int weakest = -1;
        double weakest_prom = std::numeric_limits<double>::infinity();
        for (int i = 0; i < m; ++i) {
            if (!ext[static_cast<std::size_t>(i)].max) continue;
            const double left = val(ext[static_cast<std::size_t>((i + m - 1) % m)]);
            const double right = val(ext[static_cast<std::size_t>((i + 1) % m)]);
            const double prom = val(ext[static_cast<std::size_t>(i)]) - std::max(left, right);
            if (prom < weakest_prom) {
                weakest_prom = prom;
                weakest = i;
            }
        }
        if (weakest < 0 || weakest_prom >= threshold) break;
        const int li = (weakest + m - 1) % m, ri = (weakest + 1) % m;
        // Remove the crest and the higher of its troughs (the lower trough survives).
        const int drop_trough = val(ext[static_cast<std::size_t>(li)]) > val(ext[static_cast<std::size_t>(ri)]) ? li : ri;
        std::vector<Ext> next;
        for (int i = 0; i < m; ++i)
            if (i != weakest && i != drop_trough) next.push_back(ext[static_cast<std::size_t>(i)]);
        ext.swap(next);
    }
    if (ext.size() < 4) {
        // One crest (or none): it counts only if it stands out from the lowest point.
        for (const Ext& e : ext)
            if (e.max && val(e) - *mn >= threshold) {
                out.node_angles_rad.push_back(kTwoPi * e.k / n);
                out.node_amplitudes_m.push_back(val(e) - out.fourier.a0);
            }
        if (out.node_angles_rad.size() > 1) { // two crests with one trough between them each way
            // (erase, not resize: GCC 12 warns falsely about resize(1) here)
            out.node_angles_rad.erase(out.node_angles_rad.begin() + 1, out.node_angles_rad.end());
            out.node_amplitudes_m.erase(out.node_amplitudes_m.begin() + 1, out.node_amplitudes_m.end());
        }
    } else {
        for (const Ext& e : ext)
            if (e.max) {
                out.node_angles_rad.push_back(kTwoPi * e.k / n);
                out.node_amplitudes_m.push_back(val(e) - out.fourier.a0);
            }
    }
    out.node_count = static_cast<int>(out.node_angles_rad.size());
}

DrapeMetrics drape_metrics(const Polygon2& outline, double R1, double R2, const MetricOptions& opt)
{
    if (!(R1 > 0) || !(R2 > 0) || R2 >= R1)
        throw ParameterError("drape_metrics: need 0 < R2 < R1, got R1 = " + std::to_string(R1) +
                             " m, R2 = " + std::to_string(R2) + " m");
    if (outline.size() < 3) throw ParameterError("drape_metrics: outline has fewer than 3 points");
    DrapeMetrics m;
    double a2 = 0;
    for (std::size_t i = 0, n = outline.size(); i < n; ++i) a2 += cross2(outline[i], outline[(i + 1) % n]);
    m.shadow_area_m2 = std::abs(a2) / 2;
    const double disc = std::numbers::pi * R2 * R2;
    m.drape_coefficient_percent = (m.shadow_area_m2 - disc) / (std::numbers::pi * R1 * R1 - disc) * 100.0;
    m.profile = radial_profile(outline, opt.samples);
    m.fourier = fourier_fit(m.profile, opt.smoothing_harmonics);
    double sum = 0, mn = std::numeric_limits<double>::infinity(), mx = -mn;
    int cnt = 0;
    for (double r : m.profile.r)
        if (!std::isnan(r)) {
            sum += r;
            mn = std::min(mn, r);
            mx = std::max(mx, r);
            ++cnt;
        }
    m.mean_radius_m = cnt ? sum / cnt : kNaN;
    m.min_radius_m = mn;
    m.max_radius_m = mx;
    find_nodes(m.profile, opt, m);
    return m;
}

Polygon2 shadow_outline(const Positions& X, const Triangles& F, int samples)
{
    std::vector<double> r(static_cast<std::size_t>(samples), kNaN);
    for (int t = 0; t < F.rows(); ++t)
        for (int e = 0; e < 3; ++e) {
            const auto a = X.row(F(t, e));
            const auto b = X.row(F(t, (e + 1) % 3));
            accumulate_segment({a(0), a(1)}, {b(0), b(1)}, r);
        }
    RadialProfile p;
    p.r = std::move(r);
    return polygon_from_profile(p);
}

RadialProfile slice_profile(const Positions& X, const Triangles& F, double z_plane, int samples)
{
    RadialProfile p;
    p.r.assign(static_cast<std::size_t>(samples), kNaN);
    for (int t = 0; t < F.rows(); ++t) {
        Eigen::Vector2d pts[3];
        int np = 0;
        for (int e = 0; e < 3 && np < 3; ++e) {
            const Eigen::Vector3d a = X.row(F(t, e));
            const Eigen::Vector3d b = X.row(F(t, (e + 1) % 3));
            const double da = a.z() - z_plane, db = b.z() - z_plane;
            if ((da < 0) == (db < 0)) continue;
            const double s = da / (da - db);
            const Eigen::Vector3d c = a + s * (b - a);
            pts[np++] = {c.x(), c.y()};
        }
        if (np == 2) accumulate_segment(pts[0], pts[1], p.r);
    }
    return p;
}

HemProfile hem_profile(const Positions& X, const std::vector<char>& boundary)
{
    HemProfile h;
    for (int i = 0; i < X.rows(); ++i) {
        if (!boundary[static_cast<std::size_t>(i)]) continue;
        h.theta.push_back(std::atan2(X(i, 1), X(i, 0)));
        h.z.push_back(X(i, 2));
    }
    if (!h.z.empty()) {
        h.min_z = *std::min_element(h.z.begin(), h.z.end());
        h.max_z = *std::max_element(h.z.begin(), h.z.end());
        double s = 0;
        for (double z : h.z) s += z;
        h.mean_z = s / static_cast<double>(h.z.size());
    }
    return h;
}

} // namespace drape::cloth
