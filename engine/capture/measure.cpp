#include "engine/capture/measure.hpp"

#include "engine/capture/image.hpp"
#include "engine/core/error.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace drape::capture {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string fmt(const char* f, double v)
{
    char buf[96];
    std::snprintf(buf, sizeof buf, f, v);
    return buf;
}

/// BGR 8-bit -> smoothed CIE L*a*b* float (L 0..100). A small Gaussian removes
/// sensor noise and JPEG blocking; it is symmetric so it does not move an edge.
cv::Mat to_lab(const cv::Mat& bgr)
{
    cv::Mat f, lab;
    bgr.convertTo(f, CV_32F, 1.0 / 255.0);
    cv::cvtColor(f, lab, cv::COLOR_BGR2Lab);
    cv::GaussianBlur(lab, lab, cv::Size(0, 0), 1.0);
    return lab;
}

cv::Vec3f sample(const cv::Mat& lab, const Eigen::Vector2d& px)
{
    const int x = std::clamp(static_cast<int>(std::lround(px.x())), 0, lab.cols - 1);
    const int y = std::clamp(static_cast<int>(std::lround(px.y())), 0, lab.rows - 1);
    return lab.at<cv::Vec3f>(y, x);
}

double median(std::vector<double> v)
{
    if (v.empty()) return kNaN;
    auto mid = v.begin() + static_cast<long>(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    return *mid;
}

/// Bilinear sample of a single-channel float map; outside -> 0.
double bilinear(const cv::Mat& m, double x, double y)
{
    if (!(x >= 0 && y >= 0 && x <= m.cols - 1 && y <= m.rows - 1)) return 0.0;
    const int x0 = std::min(static_cast<int>(x), m.cols - 2), y0 = std::min(static_cast<int>(y), m.rows - 2);
    const double fx = x - x0, fy = y - y0;
    const float* r0 = m.ptr<float>(y0);
    const float* r1 = m.ptr<float>(y0 + 1);
    return (1 - fy) * ((1 - fx) * r0[x0] + fx * r0[x0 + 1]) + fy * ((1 - fx) * r1[x0] + fx * r1[x0 + 1]);
}

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

// ---- segmentation -------------------------------------------------------------

FabricModel fabric_model(const record::Record& rec, const record::Camera& cam, const cv::Mat& lab)
{
    FabricModel m;
    std::vector<double> L, A, B;
    // Fabric: the pedestal top is always covered by the specimen.
    for (double r = 0; r <= 0.6 * rec.R2; r += 0.003)
        for (int k = 0; k < 90; ++k) {
            const double th = 2 * M_PI * k / 90;
            const cv::Vec3f v = sample(lab, cam.project({r * std::cos(th), r * std::sin(th), 0.0}));
            L.push_back(v[0]);
            A.push_back(v[1]);
            B.push_back(v[2]);
        }
    m.fabric_lab = {median(L), median(A), median(B)};
    double var = 0;
    for (double l : L) var += (l - m.fabric_lab[0]) * (l - m.fabric_lab[0]);
    m.fabric_L_sd = std::sqrt(var / static_cast<double>(L.size()));
    // Floor: a ring beyond the specimen's reach and inside the chessboards.
    L.clear();
    A.clear();
    B.clear();
    for (double r = rec.R1 + 0.035; r <= rec.R1 + 0.06; r += 0.005)
        for (int k = 0; k < 180; ++k) {
            const double th = 2 * M_PI * k / 180;
            const Eigen::Vector2d px = cam.project({r * std::cos(th), r * std::sin(th), -rec.pedestal_height});
            if (!(px.x() >= 0 && px.y() >= 0 && px.x() < lab.cols && px.y() < lab.rows)) continue;
            const cv::Vec3f v = sample(lab, px);
            L.push_back(v[0]);
            A.push_back(v[1]);
            B.push_back(v[2]);
        }
    m.floor_lab = {median(L), median(A), median(B)};
    const double chroma = std::hypot(m.fabric_lab[1] - m.floor_lab[1], m.fabric_lab[2] - m.floor_lab[2]);
    // Shadows on the white floor are grey: they change L* but hardly a*, b*.
    // A coloured fabric is therefore segmented by chroma alone, which ignores
    // its own shading and the floor's shadows; a grey fabric by darkness.
    m.chromatic = chroma >= 12.0;
    m.contrast = m.chromatic ? chroma : std::abs(m.floor_lab[0] - m.fabric_lab[0]);
    return m;
}

cv::Mat fabric_probability(const cv::Mat& lab, const FabricModel& m)
{
    cv::Mat p(lab.size(), CV_32F);
    const double da = m.fabric_lab[1] - m.floor_lab[1], db = m.fabric_lab[2] - m.floor_lab[2];
    const double n2 = da * da + db * db;
    // Grey fabric: p = 0.5 at max(6, 3 sd) L* units above the fabric's own level,
    // i.e. as close to the fabric as its noise allows, because the contact
    // shadow around the hem is dark too.
    const double half = std::max(6.0, 3.0 * m.fabric_L_sd);
    const bool darker = m.fabric_lab[0] < m.floor_lab[0];
    for (int y = 0; y < lab.rows; ++y) {
        const cv::Vec3f* in = lab.ptr<cv::Vec3f>(y);
        float* out = p.ptr<float>(y);
        for (int x = 0; x < lab.cols; ++x) {
            double v;
            if (m.chromatic)
                v = ((in[x][1] - m.floor_lab[1]) * da + (in[x][2] - m.floor_lab[2]) * db) / n2;
            else if (darker)
                v = 1.0 - (in[x][0] - m.fabric_lab[0]) / (2 * half);
            else
                v = 1.0 - (m.fabric_lab[0] - in[x][0]) / (2 * half);
            out[x] = static_cast<float>(std::clamp(v, 0.0, 1.0));
        }
    }
    return p;
}

namespace {

/// Binary mask of the fabric component around the pedestal axis, dilated a
/// little so the sub-pixel edge search is not cut; everything else (boards,
/// specks) is excluded.
cv::Mat central_component(const cv::Mat& prob, const Eigen::Vector2d& centre, double max_radius_px)
{
    cv::Mat bin = prob >= 0.5;
    cv::Mat limit = cv::Mat::zeros(prob.size(), CV_8U);
    cv::circle(limit, cv::Point(static_cast<int>(centre.x()), static_cast<int>(centre.y())),
               static_cast<int>(max_radius_px), 255, cv::FILLED);
    bin &= limit;
    cv::morphologyEx(bin, bin, cv::MORPH_OPEN, cv::getStructuringElement(cv::MORPH_ELLIPSE, {3, 3}));
    cv::Mat labels;
    cv::connectedComponents(bin, labels, 8, CV_32S);
    const int cxp = std::clamp(static_cast<int>(centre.x()), 0, prob.cols - 1);
    const int cyp = std::clamp(static_cast<int>(centre.y()), 0, prob.rows - 1);
    const int id = labels.at<int>(cyp, cxp);
    cv::Mat gate = cv::Mat::zeros(prob.size(), CV_8U);
    if (id == 0) return gate;
    gate = labels == id;
    cv::dilate(gate, gate, cv::getStructuringElement(cv::MORPH_ELLIPSE, {5, 5}));
    return gate;
}

void measure_top(const record::Record& rec, const MeasureOptions& opt, const record::ContourStack* stack, Measurement& out)
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
void measure_side(const record::Record& rec, Measurement& out)
{
    const record::Camera& cam = rec.cameras.at("side");
    SideView& sv = out.side;
    const cv::Mat lab = to_lab(out.side_image);
    const FabricModel& fm = out.top.model;
    const double da = fm.fabric_lab[1] - fm.floor_lab[1], db = fm.fabric_lab[2] - fm.floor_lab[2];
    const double n2 = std::max(da * da + db * db, 1e-9);
    // The camera's azimuth: hem points in front of the disc are between the
    // camera and the axis; the back hem is hidden by the pedestal there.
    const Eigen::Vector3d o = cam.centre();
    const Eigen::Vector2d toward(-o.x(), -o.y());
    const Eigen::Vector2d side_dir = Eigen::Vector2d(-toward.y(), toward.x()).normalized();
    const Eigen::Vector2d front = -toward.normalized() * rec.R2;
    std::vector<double> diffs;
    for (int i = -40; i <= 40; ++i) {
        const double lateral = 0.8 * rec.R2 * i / 40.0; // stay off the pedestal's silhouette edges
        const double depth = std::sqrt(rec.R2 * rec.R2 - lateral * lateral);
        const Eigen::Vector2d p2 = -toward.normalized() * depth + side_dir * lateral;
        (void)front;
        const Eigen::Vector2d bottom = cam.project({p2.x(), p2.y(), -0.9 * rec.pedestal_height});
        const Eigen::Vector2d top = cam.project({p2.x(), p2.y(), 0.0});
        const int u = static_cast<int>(std::lround(bottom.x()));
        if (u < 0 || u >= lab.cols) continue;
        // Pedestal colour at the column's bottom: the reference the hem stands out from.
        const cv::Vec3f ped = sample(lab, bottom);
        int hit = -1;
        for (int v = static_cast<int>(bottom.y()); v > static_cast<int>(top.y()) - 3 && v > 1; --v) {
            auto is_fabric = [&](int vv) {
                const cv::Vec3f px = lab.at<cv::Vec3f>(vv, u);
                if (fm.chromatic) return ((px[1] - ped[1]) * da + (px[2] - ped[2]) * db) / n2 >= 0.4;
                return px[0] < 0.5 * (ped[0] + fm.fabric_lab[0]);
            };
            if (is_fabric(v) && is_fabric(v - 1)) {
                hit = v;
                break;
            }
        }
        if (hit < 0) continue;
        const Eigen::Vector2d px(u, hit + 0.5); // edge between the last pedestal pixel and the fabric
        // World point: march the pixel's ray from the camera to the first point
        // inside the top-view outline (the hem lies on the shadow outline).
        const Eigen::Vector3d d = cam.ray(px);
        Eigen::Vector3d hem(kNaN, kNaN, kNaN);
        const auto& prof = out.top.metrics.profile;
        for (double s = 0.5; s < 1.5; s += 0.0002) {
            const Eigen::Vector3d X = o + s * d;
            double th = std::atan2(X.y(), X.x());
            if (th < 0) th += 2 * M_PI;
            const int k = static_cast<int>(std::lround(th / (2 * M_PI) * prof.size())) % prof.size();
            const double r = prof.r[static_cast<std::size_t>(k)];
            if (std::isfinite(r) && std::hypot(X.x(), X.y()) <= r) {
                hem = X;
                break;
            }
        }
        if (!std::isfinite(hem.x())) continue;
        sv.hem_px.push_back(px);
        sv.hem_world.push_back(hem);
        double th = std::atan2(hem.y(), hem.x());
        if (th < 0) th += 2 * M_PI;
        if (!(hem.z() >= sv.hem_min_z)) {
            sv.hem_min_z = hem.z();
            sv.hem_min_theta = th;
        }
        // Height model of the top view at the same angle.
        const int n = static_cast<int>(out.top.outline_z.size());
        if (n > 0) {
            double best_d = 1e9;
            double zm = kNaN;
            for (int j = 0; j < n; ++j) {
                double tj = std::atan2(out.top.outline[static_cast<std::size_t>(j)].y(), out.top.outline[static_cast<std::size_t>(j)].x());
                if (tj < 0) tj += 2 * M_PI;
                double dd = std::abs(tj - th);
                dd = std::min(dd, 2 * M_PI - dd);
                if (dd < best_d) {
                    best_d = dd;
                    zm = out.top.outline_z[static_cast<std::size_t>(j)];
                }
            }
            diffs.push_back(hem.z() - zm);
        }
    }
    sv.columns = static_cast<int>(sv.hem_px.size());
    if (sv.columns < 10) {
        out.not_measured.push_back("side view: hem not found in front of the pedestal in " + cam.image);
        return;
    }
    double s2 = 0;
    for (double d : diffs) s2 += d * d;
    if (!diffs.empty()) sv.model_rms_diff = std::sqrt(s2 / static_cast<double>(diffs.size()));
    if (sv.model_rms_diff > 0.01)
        sv.warnings.push_back("side view: hem heights differ from the top view's height model by " +
                              fmt("%.1f", sv.model_rms_diff * 1e3) + " mm RMS");
    sv.measured = true;
    out.measured.push_back("side view: hem height in front of the pedestal");
}

void measure_contours(const record::Record& rec, const record::ContourStack& st, Measurement& out)
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
        lv.harmonics = cloth::choose_harmonics(p, rec.contour_sigma, max_h);
        lv.fit = cloth::fourier_fit(p, lv.harmonics);
        lv.residual_rms = cloth::fourier_residual_rms(p, lv.fit);
        // Guard: the seed interpolates each contour by its Fourier series, so the
        // series must reproduce the points to the profiler's noise. Where the
        // BIC-like stop of choose_harmonics ends above it (fine wrinkles), add
        // harmonics until the residual is down to the noise (10 % margin for
        // the sigma's own uncertainty).
        auto floor_ok = [&](int, double res) { return res <= 1.1 * rec.contour_sigma; };
        if (!floor_ok(lv.harmonics, lv.residual_rms)) {
            int lo = lv.harmonics, hi = max_h;
            cloth::FourierSeries fhi = cloth::fourier_fit(p, hi);
            if (floor_ok(hi, cloth::fourier_residual_rms(p, fhi))) {
                while (hi - lo > 1) {
                    const int mid = (lo + hi) / 2;
                    if (floor_ok(mid, cloth::fourier_residual_rms(p, cloth::fourier_fit(p, mid))))
                        hi = mid;
                    else
                        lo = mid;
                }
                lv.harmonics = hi;
                lv.fit = cloth::fourier_fit(p, hi);
                lv.residual_rms = cloth::fourier_residual_rms(p, lv.fit);
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

} // namespace

Measurement measure_record(const record::Record& rec, const MeasureOptions& opt)
{
    Measurement out;
    out.specimen_id = rec.specimen_id;
    out.lab_dc_percent = rec.lab_drape_coefficient_percent;
    for (const auto& k : rec.unknown_fields) out.warnings.push_back("meta.json: unknown field '" + k + "' kept, not used");

    std::optional<record::ContourStack> stack;
    if (std::filesystem::exists(rec.file(rec.contours_file))) {
        try {
            stack = record::read_contours(rec);
            measure_contours(rec, *stack, out);
        } catch (const Error& e) {
            out.not_measured.push_back(std::string("laser contours: ") + e.what());
            stack.reset();
        }
    } else {
        out.not_measured.push_back("laser contours: " + rec.contours_file + " not in the record");
    }

    auto load = [&](const std::string& station, cv::Mat& img) {
        if (!rec.has_camera(station)) {
            out.not_measured.push_back(station + " view: no 'cameras." + station + "' in meta.json");
            return false;
        }
        if (!std::filesystem::exists(rec.file(rec.cameras.at(station).image))) {
            out.not_measured.push_back(station + " view: " + rec.cameras.at(station).image + " not in the record");
            return false;
        }
        try {
            img = load_image(rec, station);
            return true;
        } catch (const Error& e) {
            out.not_measured.push_back(station + " view: " + e.what());
            return false;
        }
    };

    if (load("top", out.top_image)) measure_top(rec, opt, stack ? &*stack : nullptr, out);
    if (!out.top.measured)
        out.not_measured.push_back("drape coefficient and nodes: need a usable top view");
    if (load("side", out.side_image)) {
        if (out.top.measured)
            measure_side(rec, out);
        else
            out.not_measured.push_back("side view: hem height needs the top view's outline");
    }
    if (rec.has_camera("iso"))
        out.not_measured.push_back(
            std::filesystem::exists(rec.file(rec.cameras.at("iso").image))
                ? "iso view: not analysed by this version (for a person checking the drape)"
                : "iso view: " + rec.cameras.at("iso").image + " not in the record");

    if (out.top.measured) {
        // Height error of the model: what the side view measured where it can
        // see the hem, never less than 3 mm; 10 mm when there is no side view.
        const double dz = out.side.measured ? std::max(out.side.model_rms_diff, 0.003) : 0.010;
        out.top.height_error_m = dz;
        out.top.dc_uncertainty_percent = std::hypot(out.top.dc_edge_term, out.top.dc_per_metre_height * dz);
    }

    // Lowest hem point: the lowest of the evidence. The top view's height
    // model covers every angle; the side view sees the front hem directly.
    if (out.top.measured && !out.top.outline_z.empty()) {
        out.hem_min_height = *std::min_element(out.top.outline_z.begin(), out.top.outline_z.end());
        out.hem_min_source = std::string("top-view silhouette back-projected with the height model (") +
                             to_string(out.top.height_model) + ")";
    }
    if (out.side.measured && (!out.hem_min_height || out.side.hem_min_z < *out.hem_min_height)) {
        out.hem_min_height = out.side.hem_min_z;
        out.hem_min_source = "side-view silhouette against the pedestal";
    }
    if (!out.hem_min_height && stack && !stack->depths.empty()) {
        // Only a bound: the hem is at least as deep as the deepest closed cut.
        out.hem_min_height = -*std::max_element(stack->depths.begin(), stack->depths.end());
        out.hem_min_source = "deepest closed laser contour (upper bound: the hem is lower still)";
    }
    if (!out.hem_min_height) out.not_measured.push_back("hem height: needs the top view, side view or contours");
    for (const auto& w : out.top.warnings) out.warnings.push_back(w);
    for (const auto& w : out.side.warnings) out.warnings.push_back(w);
    return out;
}

// ---- report -------------------------------------------------------------------

namespace {

nlohmann::ordered_json num(double v)
{
    return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr);
}

} // namespace

nlohmann::ordered_json to_json(const Measurement& m)
{
    using json = nlohmann::ordered_json;
    json j;
    j["specimen_id"] = m.specimen_id;
    j["lab_drape_coefficient_percent"] = m.lab_dc_percent ? json(*m.lab_dc_percent) : json(nullptr);
    const auto& t = m.top;
    json top_block;
    if (t.measured) {
        j["drape_coefficient_percent"] = t.metrics.drape_coefficient_percent;
        j["drape_coefficient_uncertainty_percent"] = t.dc_uncertainty_percent;
        j["node_count"] = t.metrics.node_count;
        json ang = json::array(), amp = json::array();
        for (double a : t.metrics.node_angles_rad) ang.push_back(a * 180.0 / M_PI);
        for (double a : t.metrics.node_amplitudes_m) amp.push_back(a);
        j["node_angles_deg"] = ang;
        j["node_amplitudes_m"] = amp;
        json top;
        top["height_model"] = to_string(t.height_model);
        top["drape_coefficient_plane_percent"] = t.dc_plane_percent;
        top["drape_coefficient_chord_percent"] = t.dc_chord_percent;
        top["drape_coefficient_contours_percent"] = num(t.dc_contours_percent);
        top["shadow_area_m2"] = t.metrics.shadow_area_m2;
        top["mean_radius_m"] = t.metrics.mean_radius_m;
        top["min_radius_m"] = t.metrics.min_radius_m;
        top["max_radius_m"] = t.metrics.max_radius_m;
        top["rays_beyond_reach"] = t.rays_beyond_reach;
        top["height_error_m"] = t.height_error_m;
        top["drape_coefficient_edge_error_percent"] = t.dc_edge_term;
        top["segmentation"] = {{"by", t.model.chromatic ? "chroma" : "darkness"},
                               {"contrast_lab", t.model.contrast},
                               {"fabric_lab", {t.model.fabric_lab[0], t.model.fabric_lab[1], t.model.fabric_lab[2]}},
                               {"floor_lab", {t.model.floor_lab[0], t.model.floor_lab[1], t.model.floor_lab[2]}}};
        json mags = json::array();
        for (int k = 1; k <= std::min(12, t.metrics.fourier.harmonics()); ++k) mags.push_back(t.metrics.fourier.magnitude(k));
        top["outline_fourier_a0_m"] = t.metrics.fourier.a0;
        top["outline_fourier_magnitudes_m"] = mags;
        json rt = json::array();
        const auto& pr = t.metrics.profile;
        const int stride = std::max(1, pr.size() / 360);
        for (int k = 0; k < pr.size(); k += stride) rt.push_back(num(pr.r[static_cast<std::size_t>(k)]));
        top["r_theta_m"] = rt;
        top["r_theta_step_deg"] = 360.0 * stride / std::max(1, pr.size());
        top_block = top;
    } else {
        j["drape_coefficient_percent"] = nullptr;
        j["node_count"] = nullptr;
        j["node_angles_deg"] = nullptr;
    }
    j["hem_min_height_m"] = m.hem_min_height ? json(*m.hem_min_height) : json(nullptr);
    j["hem_min_height_source"] = m.hem_min_source;
    if (!top_block.is_null()) j["top"] = top_block;
    if (m.top_calibration) {
        const auto& c = *m.top_calibration;
        j["calibration_top"] = {{"pose", c.ok ? "measured (solvePnP on the floor chessboards)" : "declared"},
                                {"boards_found", c.boards_found},
                                {"boards_missed", c.boards_missed},
                                {"corners", c.corners},
                                {"reprojection_rms_px", c.rms_px_measured},
                                {"declared_pose_rms_px", c.rms_px_declared},
                                {"rotation_diff_deg", c.rotation_diff_deg},
                                {"centre_diff_m", c.centre_diff_m},
                                {"max_shift_over_specimen_px", c.max_shift_px}};
    }
    if (m.side.measured)
        j["side"] = {{"columns", m.side.columns},
                     {"hem_min_height_m", m.side.hem_min_z},
                     {"hem_min_theta_deg", m.side.hem_min_theta * 180.0 / M_PI},
                     {"drape_depth_m", -m.side.hem_min_z},
                     {"rms_diff_to_top_height_model_m", num(m.side.model_rms_diff)}};
    json cs = json::array();
    for (const auto& c : m.contours) {
        json mags = json::array();
        for (int k = 1; k <= c.harmonics; ++k) mags.push_back(c.fit.magnitude(k));
        cs.push_back({{"depth_m", c.depth},
                      {"points", c.points},
                      {"closed", c.complete},
                      {"mean_radius_m", c.mean_radius},
                      {"harmonics", c.harmonics},
                      {"fourier_magnitudes_m", mags},
                      {"residual_rms_m", c.residual_rms},
                      {"max_jump_between_rays_m", c.max_jump},
                      {"noise_sigma_m", c.noise_sigma}});
    }
    j["contours"] = cs;
    j["measured"] = m.measured;
    j["not_measured"] = m.not_measured;
    j["warnings"] = m.warnings;
    return j;
}

cv::Mat draw_top_overlay(const record::Record& rec, const Measurement& m)
{
    if (m.top_image.empty()) throw ParameterError("draw_top_overlay: the record has no readable top photo");
    const record::Camera cam = m.top_calibration && m.top_calibration->ok ? m.top_calibration->measured : rec.cameras.at("top");
    // Crop to the specimen's reach and enlarge 2x with cubic interpolation, so
    // a person can judge the traced edge to a fraction of a pixel.
    constexpr double zoom = 2.0;
    const Eigen::Vector2d c0 = cam.project({0, 0, 0});
    const double reach = (cam.project({rec.R1 * 1.12, 0, 0}) - c0).norm();
    cv::Rect roi(static_cast<int>(c0.x() - reach), static_cast<int>(c0.y() - reach), static_cast<int>(2 * reach),
                 static_cast<int>(2 * reach) + 40);
    roi.y -= 40;
    roi &= cv::Rect(0, 0, m.top_image.cols, m.top_image.rows);
    cv::Mat img;
    cv::resize(m.top_image(roi), img, {}, zoom, zoom, cv::INTER_CUBIC);
    constexpr int shift = 2; // sub-pixel drawing: coordinates * 4
    auto P = [&](const Eigen::Vector2d& p) {
        return cv::Point(static_cast<int>(std::lround(((p.x() - roi.x + 0.5) * zoom - 0.5) * (1 << shift))),
                         static_cast<int>(std::lround(((p.y() - roi.y + 0.5) * zoom - 0.5) * (1 << shift))));
    };
    auto Pi = [&](const Eigen::Vector2d& p) {
        const cv::Point q = P(p);
        return cv::Point(q.x >> shift, q.y >> shift);
    };
    auto circle_world = [&](double r, double z, const cv::Scalar& col) {
        std::vector<cv::Point> pts;
        for (int k = 0; k < 360; ++k) {
            const double a = 2 * M_PI * k / 360;
            pts.push_back(P(cam.project({r * std::cos(a), r * std::sin(a), z})));
        }
        cv::polylines(img, pts, true, col, 1, cv::LINE_AA, shift);
    };
    circle_world(rec.R2, 0.0, cv::Scalar(255, 255, 0));  // pedestal edge (cyan)
    circle_world(rec.R1, 0.0, cv::Scalar(150, 150, 150)); // flat specimen, for scale
    const auto& t = m.top;
    if (t.measured) {
        std::vector<cv::Point> pts;
        for (const auto& p : t.outline_px) pts.push_back(P(p));
        cv::polylines(img, pts, true, cv::Scalar(0, 230, 0), 1, cv::LINE_AA, shift);
        const int n = static_cast<int>(t.outline.size());
        for (std::size_t i = 0; i < t.metrics.node_angles_rad.size(); ++i) {
            const double a = t.metrics.node_angles_rad[i];
            int best = 0;
            double bd = 1e9;
            for (int k = 0; k < n; ++k) {
                const auto& q = t.outline[static_cast<std::size_t>(k)];
                double tk = std::atan2(q.y(), q.x());
                if (tk < 0) tk += 2 * M_PI;
                double d = std::abs(tk - a);
                d = std::min(d, 2 * M_PI - d);
                if (d < bd) {
                    bd = d;
                    best = k;
                }
            }
            const Eigen::Vector2d p = t.outline_px[static_cast<std::size_t>(best)];
            // Tick from the pedestal edge out to the crest: the fold's axis.
            const Eigen::Vector2d e = cam.project({rec.R2 * std::cos(a), rec.R2 * std::sin(a), 0.0});
            cv::line(img, P(e), P(p), cv::Scalar(0, 190, 255), 1, cv::LINE_AA, shift);
            cv::circle(img, Pi(p), 7, cv::Scalar(0, 190, 255), 2, cv::LINE_AA);
            const Eigen::Vector2d lab = p + (p - c0).normalized() * 12.0;
            cv::putText(img, std::to_string(i + 1), Pi(lab) + cv::Point(-6, 6), cv::FONT_HERSHEY_SIMPLEX, 0.6,
                        cv::Scalar(0, 90, 230), 2, cv::LINE_AA);
        }
        char buf[200];
        std::snprintf(buf, sizeof buf, "%s  D = %.1f%% +-%.1f  nodes %d", m.specimen_id.c_str(),
                      t.metrics.drape_coefficient_percent, t.dc_uncertainty_percent, t.metrics.node_count);
        std::string text = buf;
        if (m.lab_dc_percent) text += "  (lab " + fmt("%.1f%%", *m.lab_dc_percent) + ")";
        cv::putText(img, text, {10, 28}, cv::FONT_HERSHEY_SIMPLEX, 0.75, cv::Scalar(0, 0, 0), 2, cv::LINE_AA);
    } else {
        cv::putText(img, m.specimen_id + ": top view not measured", {10, 28}, cv::FONT_HERSHEY_SIMPLEX, 0.75,
                    cv::Scalar(0, 0, 255), 2, cv::LINE_AA);
    }
    return img;
}

double gider_drape_coefficient(const KesValues& k)
{
    // Gider (2004), as quoted in the seed paper, section 5.2.
    return 69.17 + 25.51 * k.two_hb - 35.69 * k.miu + 3.50 * k.g + 0.00049 * k.rt + 21.13 * k.wc - 0.492 * k.rc -
           13.04 * k.t0 + 0.303 * k.emc + 0.51 * k.w;
}

} // namespace drape::capture
