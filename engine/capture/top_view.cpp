#include "engine/capture/top_view.hpp"

#include "engine/capture/calibrate.hpp"
#include "engine/capture/pixels.hpp"
#include "engine/capture/steps.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace drape::capture {

using namespace detail;

namespace {

/// A vertical section curve (r, z) [m] of the height model along one ray,
/// ordered from the outermost point inwards, with the arc length from the
/// disc edge of each vertex (negative = beyond the model's hem, outermost first).
struct Section {
    std::vector<Eigen::Vector2d> rz;
    std::vector<double> arc;
};

void append_segment(Section& s, const Eigen::Vector2d& a, const Eigen::Vector2d& b, double arc_a, double arc_b, double step)
{
    const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / step)));
    for (int i = (s.rz.empty() ? 0 : 1); i <= n; ++i) {
        const double t = static_cast<double>(i) / n;
        s.rz.push_back(a + t * (b - a));
        s.arc.push_back(arc_a + t * (arc_b - arc_a));
    }
}

/// Section of the chosen height model at ray angle `theta` [rad]. Marching
/// step 0.2 mm: well below the 0.7 mm footprint of one top-view pixel.
Section make_section(HeightModel model, double R1, double R2, const record::ContourStack* stack, int k_contour)
{
    constexpr double step = 0.2e-3, beyond = 0.02;
    const double L = R1 - R2; // hanging length of a radial fibre
    Section s;
    if (model == HeightModel::Plane) {
        append_segment(s, {R1 + beyond, 0}, {0.3 * R2, 0}, -beyond, L + R2 - 0.3 * R2, step);
        return s;
    }
    if (model == HeightModel::Chord) {
        append_segment(s, {R1 + beyond, 0}, {R1, 0}, L + beyond, L, step);
        // Circle of radius L around the disc edge: a straight, inextensible
        // radial fibre hanging at angle phi below horizontal.
        const int n = static_cast<int>(std::ceil(L * M_PI / 2 / step));
        for (int i = 1; i <= n; ++i) {
            const double phi = (M_PI / 2) * i / n;
            s.rz.emplace_back(R2 + L * std::cos(phi), -L * std::sin(phi));
            s.arc.push_back(L);
        }
        return s;
    }
    // Contours: polyline from the disc edge through the measured levels,
    // extended straight along its last segment until its arc length is L.
    std::vector<Eigen::Vector2d> pts{{R2, 0.0}};
    for (std::size_t d = 0; d < stack->depths.size(); ++d) {
        const auto& p = stack->profiles[d];
        if (k_contour < 0 || k_contour >= p.size()) continue;
        const double r = p.r[static_cast<std::size_t>(k_contour)];
        if (std::isfinite(r)) pts.emplace_back(r, -stack->depths[d]);
    }
    std::vector<double> arc{0.0};
    for (std::size_t i = 1; i < pts.size(); ++i) arc.push_back(arc.back() + (pts[i] - pts[i - 1]).norm());
    Eigen::Vector2d dir(0, -1);
    if (pts.size() >= 2) dir = (pts.back() - pts[pts.size() - 2]).normalized();
    const double rest = L - arc.back();
    const Eigen::Vector2d hem = pts.back() + std::max(rest, 0.0) * dir;
    const Eigen::Vector2d far = hem + beyond * dir;
    append_segment(s, far, hem, L + beyond, std::max(L, arc.back()), step);
    append_segment(s, hem, pts.back(), std::max(L, arc.back()), arc.back(), step);
    for (std::size_t i = pts.size() - 1; i >= 1; --i) append_segment(s, pts[i], pts[i - 1], arc[i], arc[i - 1], step);
    return s;
}

struct Trace {
    cloth::Polygon2 outline;
    std::vector<double> z, arc;
    std::vector<Eigen::Vector2d> px;
    int beyond = 0, missed = 0;
};

/// Outermost fabric point along every ray: march each section from outside in
/// and stop at the first point whose image is fabric (p >= 0.5 inside the
/// central component); the crossing is interpolated linearly in p.
Trace trace_outline(const record::Camera& cam, const cv::Mat& prob, const cv::Mat& gate, HeightModel model, double R1,
                    double R2, const record::ContourStack* stack, int rays, const cv::Mat& lightness)
{
    Trace tr;
    const double L = R1 - R2;
    for (int k = 0; k < rays; ++k) {
        const double th = 2 * M_PI * k / rays;
        const double c = std::cos(th), s = std::sin(th);
        int kc = -1;
        if (stack && !stack->profiles.empty()) {
            const int n = stack->profiles.front().size();
            kc = static_cast<int>(std::lround(th / (2 * M_PI) * n)) % n;
        }
        const Section sec = make_section(model, R1, R2, stack, kc);
        double prev_p = 0;
        bool found = false;
        for (std::size_t i = 0; i < sec.rz.size(); ++i) {
            const Eigen::Vector3d X(sec.rz[i].x() * c, sec.rz[i].x() * s, sec.rz[i].y());
            const Eigen::Vector2d u = cam.project(X);
            if (!std::isfinite(u.x())) continue;
            const int gx = static_cast<int>(std::lround(u.x())), gy = static_cast<int>(std::lround(u.y()));
            const bool inside = gx >= 0 && gy >= 0 && gx < gate.cols && gy < gate.rows && gate.at<uchar>(gy, gx);
            const double p = inside ? bilinear(prob, u.x(), u.y()) : 0.0;
            if (p >= 0.5) {
                double f = 0; // fraction of the way back to the previous (outer) sample
                if (i > 0 && p > prev_p) f = (p - 0.5) / (p - prev_p);
                std::size_t j = i > 0 ? i - 1 : i;
                if (!lightness.empty()) {
                    // Grey fabric: the first pass thresholds close to the
                    // fabric's own L* (the contact shadow is dark too), which
                    // lies inside the blurred edge. Re-place the edge at the
                    // midpoint between the L* levels 2.5..4.5 px inside and
                    // outside it, i.e. where a symmetric blur puts the true edge.
                    auto img = [&](std::size_t q) {
                        return cam.project({sec.rz[q].x() * c, sec.rz[q].x() * s, sec.rz[q].y()});
                    };
                    const Eigen::Vector2d ui = img(i);
                    double lin = 0, lout = 0;
                    int nin = 0, nout = 0;
                    const std::size_t lo = i > 600 ? i - 600 : 0, hi = std::min(sec.rz.size() - 1, i + 600);
                    for (std::size_t q = lo; q <= hi; ++q) {
                        const double d = (img(q) - ui).norm();
                        if (d < 2.5 || d > 4.5) continue;
                        const Eigen::Vector2d uq = img(q);
                        const double l = bilinear(lightness, uq.x(), uq.y());
                        if (q < i) {
                            lout += l;
                            ++nout;
                        } else {
                            lin += l;
                            ++nin;
                        }
                    }
                    if (nin > 0 && nout > 0 && lout / nout - lin / nin > 5.0) {
                        const double thr = 0.5 * (lin / nin + lout / nout);
                        double prev_l = kNaN;
                        for (std::size_t q = lo; q <= hi; ++q) {
                            const Eigen::Vector2d uq = img(q);
                            if (q < i && (uq - ui).norm() > 4.5) continue;
                            const double l = bilinear(lightness, uq.x(), uq.y());
                            if (l <= thr) {
                                i = q;
                                j = q > 0 ? q - 1 : q;
                                f = std::isfinite(prev_l) && prev_l > l ? (thr - l) / (prev_l - l) : 0.0;
                                break;
                            }
                            prev_l = l;
                        }
                    }
                }
                const Eigen::Vector2d rz = sec.rz[i] + f * (sec.rz[j] - sec.rz[i]);
                const double arc = sec.arc[i] + f * (sec.arc[j] - sec.arc[i]);
                tr.outline.emplace_back(rz.x() * c, rz.x() * s);
                tr.z.push_back(rz.y());
                tr.arc.push_back(arc);
                tr.px.push_back(cam.project({rz.x() * c, rz.x() * s, rz.y()}));
                if (arc > L + 1e-4 || (model == HeightModel::Chord && rz.x() > R1 + 1e-4)) ++tr.beyond;
                found = true;
                break;
            }
            prev_p = p;
        }
        if (!found) {
            ++tr.missed;
        }
    }
    return tr;
}

double shoelace_dc(const cloth::Polygon2& poly, double R1, double R2)
{
    // Only for the comparison numbers (plane/chord/contours); the reported D
    // comes from cloth::drape_metrics on the chosen outline.
    return cloth::drape_metrics(poly, R1, R2).drape_coefficient_percent;
}

} // namespace

const char* to_string(HeightModel m)
{
    switch (m) {
    case HeightModel::Plane: return "plane z=0 (uncorrected)";
    case HeightModel::Chord: return "inextensible straight fibre from the disc edge";
    case HeightModel::Contours: return "laser contours + straight extension to the fibre length";
    }
    return "?";
}

void detail::measure_top(const record::Record& rec, const MeasureOptions& opt, const record::ContourStack* stack, Measurement& out)
{
    const record::Camera& declared = rec.cameras.at("top");
    record::Camera cam = declared;
    if (opt.calibrate && !rec.boards.empty()) {
        out.top_calibration = calibrate_camera(rec, "top", out.top_image);
        for (const auto& w : out.top_calibration->warnings) out.warnings.push_back(w);
        if (out.top_calibration->ok) cam = out.top_calibration->measured;
    }
    const cv::Mat lab = to_lab(out.top_image);
    TopView& tv = out.top;
    tv.model = fabric_model(rec, cam, lab);
    if (tv.model.contrast < 8.0) {
        out.not_measured.push_back("top view: no fabric distinguishable from the floor in " + declared.image +
                                   " (colour contrast " + fmt("%.1f", tv.model.contrast) + " Lab units < 8)");
        return;
    }
    const cv::Mat prob = fabric_probability(lab, tv.model);
    const Eigen::Vector2d c0 = cam.project({0, 0, 0});
    const double reach_px = (cam.project({rec.R1 + 0.02, 0, 0}) - c0).norm();
    const cv::Mat gate = central_component(prob, c0, reach_px);
    // The fabric must at least cover the pedestal top; otherwise what sits on
    // the pedestal is not the specimen (or the photo has none).
    const double ped_px = (cam.project({rec.R2, 0, 0}) - c0).norm();
    cv::Mat disc = cv::Mat::zeros(prob.size(), CV_8U);
    cv::circle(disc, cv::Point(static_cast<int>(c0.x()), static_cast<int>(c0.y())), static_cast<int>(0.9 * ped_px), 255,
               cv::FILLED);
    const double covered = static_cast<double>(cv::countNonZero(gate & disc)) / std::max(1, cv::countNonZero(disc));
    if (covered < 0.9) {
        out.not_measured.push_back("top view: the support disc in " + declared.image + " is not covered by fabric (" +
                                   fmt("%.0f", covered * 100) + " % of it): no specimen on the stand?");
        return;
    }

    const bool have_contours = stack && !stack->profiles.empty();
    cv::Mat lightness; // L* channel, only for the grey-fabric edge refinement
    if (!tv.model.chromatic) cv::extractChannel(lab, lightness, 0);
    const Trace plane = trace_outline(cam, prob, gate, HeightModel::Plane, rec.R1, rec.R2, nullptr, opt.rays, lightness);
    const Trace chord = trace_outline(cam, prob, gate, HeightModel::Chord, rec.R1, rec.R2, nullptr, opt.rays, lightness);
    // The chord model is the one used for D: it spans every radius from R1 in
    // to the disc edge, so the silhouette is always found on it. The contour
    // model only covers the section at the ray's own angle, but in the top view
    // a trough is overhung by its neighbouring folds, whose silhouette lies off
    // that section; it is reported as a cross-check (docs/capture.md).
    const Trace best = chord;
    tv.height_model = HeightModel::Chord;
    if (have_contours) {
        const Trace cont = trace_outline(cam, prob, gate, HeightModel::Contours, rec.R1, rec.R2, stack, opt.rays, lightness);
        if (cont.outline.size() >= 8) tv.dc_contours_percent = shoelace_dc(cont.outline, rec.R1, rec.R2);
    }
    if (best.outline.size() < static_cast<std::size_t>(opt.rays) * 9 / 10) {
        out.not_measured.push_back("top view: fabric edge found on only " + std::to_string(best.outline.size()) + " of " +
                                   std::to_string(opt.rays) + " rays");
        return;
    }
    tv.dc_plane_percent = shoelace_dc(plane.outline, rec.R1, rec.R2);
    tv.dc_chord_percent = shoelace_dc(chord.outline, rec.R1, rec.R2);
    tv.outline = best.outline;
    tv.outline_z = best.z;
    tv.outline_arc = best.arc;
    tv.outline_px = best.px;
    tv.rays_beyond_reach = best.beyond;
    tv.metrics = cloth::drape_metrics(tv.outline, rec.R1, rec.R2, opt.metrics);
    double max_px = 0;
    for (const auto& u : best.px) max_px = std::max(max_px, (u - c0).norm());
    if (max_px < ped_px + 3.0) {
        // Only the pedestal top was found (in the image, nothing reaches past
        // the disc's own edge): a specimen always hangs over the disc.
        out.not_measured.push_back("top view: nothing hangs over the support disc in " + declared.image +
                                   " (outline within " + fmt("%.1f", max_px - ped_px) +
                                   " px of the disc edge): no specimen on the stand?");
        return;
    }
    // Remaining error: (1) edge placement, 0.5 px along the whole perimeter;
    // (2) the height model: a height error dz scales every radius by
    // dz / (camera height - z), so dD = 2 A dz / (H - z) / (pi (R1^2 - R2^2)).
    // dz is set in measure_record from the side view (or a default).
    double zbar = 0;
    for (double z : tv.outline_z) zbar += z;
    zbar /= static_cast<double>(tv.outline_z.size());
    const double H = cam.centre().z();
    const double ring = M_PI * (rec.R1 * rec.R1 - rec.R2 * rec.R2);
    const double px_m = (H - zbar) / cam.fx; // one pixel at the hem [m]
    tv.dc_edge_term = 2 * M_PI * tv.metrics.mean_radius_m * 0.5 * px_m / ring * 100.0;
    tv.dc_per_metre_height = 2 * tv.metrics.shadow_area_m2 / (H - zbar) / ring * 100.0;
    tv.dc_uncertainty_percent = std::hypot(tv.dc_edge_term, tv.dc_per_metre_height * 0.010);
    if (best.beyond > opt.rays / 20)
        tv.warnings.push_back("top view: on " + std::to_string(best.beyond) +
                              " rays the fabric edge lies beyond the height model's hem (shadow or segmentation spill?)");
    if (!tv.model.chromatic && tv.model.contrast < 25)
        tv.warnings.push_back("top view: grey fabric with low contrast to the floor (" + fmt("%.0f", tv.model.contrast) +
                              " L* units); the edge may include the contact shadow");
    tv.measured = true;
    out.measured.push_back("top view: drape coefficient, nodes, r(theta)");
}

/// Front hem seen against the pedestal in the side view.
} // namespace drape::capture
