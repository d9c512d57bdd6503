#include "engine/capture/exif.hpp"
#include "engine/capture/top_view.hpp"

#include "engine/capture/calibrate.hpp"
#include "engine/capture/pixels.hpp"
#include "engine/capture/steps.hpp"

#include "engine/core/error.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <complex>

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

/// Margin of the search beyond the flat specimen's edge [m].
double search_margin(double reach) { return std::max(0.02, 0.05 * reach); }

/// Section of the chosen height model at ray angle `theta` [rad]. Marching
/// step 0.2 mm: well below the 0.7 mm footprint of one top-view pixel.
/// `reach` is the flat specimen's edge on this ray; `z_plane` and `H` (camera
/// height) are for the Plane model: a plane below the disc top is searched
/// from further out, where the specimen's reach is seen at that depth.
Section make_section(HeightModel model, double reach, double R2, const record::ContourStack* stack, int k_contour,
                     double z_plane, double H)
{
    constexpr double step = 0.2e-3;
    const double beyond = search_margin(reach);
    const double L = reach - R2; // hanging length of a radial fibre
    Section s;
    if (model == HeightModel::Plane) {
        // Where the flat edge (+ margin) at the disc top is seen, in this plane.
        const double start = (reach + beyond) * (H > 0 && H > z_plane ? (H - z_plane) / H : 1.0);
        append_segment(s, {start, z_plane}, {0.3 * R2, z_plane}, -beyond, L + R2 - 0.3 * R2, step);
        return s;
    }
    if (model == HeightModel::Chord) {
        append_segment(s, {reach + beyond, 0}, {reach, 0}, L + beyond, L, step);
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
    std::vector<Eigen::Vector2d> at_limit_px;
    int beyond = 0, missed = 0, at_limit = 0;
};

/// What the tracer needs besides the images: the geometry of every ray.
struct TraceSetup {
    HeightModel model = HeightModel::Chord;
    std::vector<double> reach; ///< flat specimen edge per ray [m]
    double R2 = 0;
    const record::ContourStack* stack = nullptr;
    double z_plane = 0; ///< Plane model
    double H = 0;       ///< camera height (Plane model's search start)
};

/// Outermost fabric point along every ray: march each section from outside in
/// and stop at the first point whose image is fabric (p >= 0.5 inside the
/// central component); the crossing is interpolated linearly in p.
Trace trace_outline(const record::Camera& cam, const cv::Mat& prob, const cv::Mat& gate, const TraceSetup& ts,
                    const cv::Mat& lightness)
{
    Trace tr;
    const int rays = static_cast<int>(ts.reach.size());
    const HeightModel model = ts.model;
    const record::ContourStack* stack = ts.stack;
    for (int k = 0; k < rays; ++k) {
        const double th = 2 * M_PI * k / rays;
        const double c = std::cos(th), s = std::sin(th);
        const double reach = ts.reach[static_cast<std::size_t>(k)];
        const double L = reach - ts.R2;
        int kc = -1;
        if (stack && !stack->profiles.empty()) {
            const int n = stack->profiles.front().size();
            kc = static_cast<int>(std::lround(th / (2 * M_PI) * n)) % n;
        }
        const Section sec = make_section(model, reach, ts.R2, stack, kc, ts.z_plane, ts.H);
        double prev_p = 0;
        bool found = false, first = true;
        for (std::size_t i = 0; i < sec.rz.size(); ++i) {
            const Eigen::Vector3d X(sec.rz[i].x() * c, sec.rz[i].x() * s, sec.rz[i].y());
            const Eigen::Vector2d u = cam.project(X);
            if (!std::isfinite(u.x())) continue;
            const int gx = static_cast<int>(std::lround(u.x())), gy = static_cast<int>(std::lround(u.y()));
            const bool in_image = gx >= 0 && gy >= 0 && gx < gate.cols && gy < gate.rows;
            const bool inside = in_image && gate.at<uchar>(gy, gx);
            const double p = inside ? bilinear(prob, u.x(), u.y()) : 0.0;
            const bool was_first = first && in_image;
            if (in_image) first = false;
            if (p >= 0.5) {
                if (was_first) {
                    ++tr.at_limit;
                    tr.at_limit_px.push_back(u);
                }
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
                if (arc > L + 1e-4 || (model == HeightModel::Chord && rz.x() > reach + 1e-4)) ++tr.beyond;
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

/// D [%] and shadow area [m^2] of an outline; `Req` is the specimen's equal-area radius.
std::pair<double, double> dc_area(const cloth::Polygon2& poly, double Req, double R2)
{
    const auto m = cloth::drape_metrics(poly, Req, R2);
    return {m.drape_coefficient_percent, m.shadow_area_m2};
}

/// Orientation of a non-round specimen from the outline: the rotation that
/// brings the flat shape's strongest low harmonic (2: a rectangle's long axis;
/// 4: a square's corners) into phase with the outline's r(theta). Folds at
/// other harmonics do not disturb it; a square whose folds are not at its
/// corners is ambiguous (declare the angle then).
double estimate_angle(const record::Specimen& sp0, const cloth::Polygon2& outline)
{
    if (sp0.shape == record::Specimen::Shape::Round || outline.size() < 16) return sp0.angle;
    const cloth::RadialProfile prof = cloth::radial_profile(outline, 360);
    record::Specimen sp = sp0;
    sp.angle = 0;
    auto coeff = [](auto f, int k) {
        std::complex<double> c = 0;
        for (int j = 0; j < 360; ++j) {
            const double th = 2 * M_PI * j / 360, v = f(j, th);
            if (std::isfinite(v)) c += v * std::polar(1.0, -k * th);
        }
        return c;
    };
    int best_k = 2;
    double best_mag = -1;
    for (int k = 1; k <= 6; ++k) {
        const double mag = std::abs(coeff([&](int, double th) { return sp.reach(th); }, k));
        if (mag > best_mag * 1.2) {
            best_mag = mag;
            best_k = k;
        }
    }
    const auto c0 = coeff([&](int, double th) { return sp.reach(th); }, best_k);
    const auto cr = coeff([&](int j, double) { return prof.r[static_cast<std::size_t>(j)]; }, best_k);
    double a = -std::arg(cr / c0) / best_k;
    const double period = 2 * M_PI / best_k;
    a = std::fmod(std::fmod(a, period) + period, period);
    return a;
}

bool touches_border(const cv::Mat& region)
{
    if (region.empty()) return false;
    const int w = region.cols, h = region.rows;
    return cv::countNonZero(region.row(0)) + cv::countNonZero(region.row(h - 1)) + cv::countNonZero(region.col(0)) +
               cv::countNonZero(region.col(w - 1)) > 0;
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

namespace {

/// A model's uncertainty from its terms (independent: root sum of squares).
void sum_terms(PerspectiveValue& v)
{
    double ss = 0;
    for (const auto& t : v.terms) ss += t.points * t.points;
    v.uncertainty_percent = std::sqrt(ss);
}

/// The headline uncertainty: the chosen model's.
void set_reported_uncertainty(TopView& tv)
{
    const PerspectiveValue& chosen = tv.perspective == "hem" ? tv.hem : tv.perspective == "disc-plane" ? tv.disc_plane : tv.uncorrected;
    tv.dc_uncertainty_percent = chosen.uncertainty_percent;
}

} // namespace

void detail::set_hem_depth_error(TopView& tv, double dz)
{
    tv.height_error_m = dz;
    for (auto& t : tv.hem.terms)
        if (t.name == "hem_depth") {
            t.points = tv.dc_per_metre_height * dz;
            t.note = "the hem's height model +-" + fmt("%.1f", dz * 1e3) + " mm";
        }
    sum_terms(tv.hem);
    set_reported_uncertainty(tv);
}

namespace {

/// The top camera: solved from a single photo's scale reference, or the record's
/// calibration (its pose measured on the floor chessboards when asked).
ViewGeometry top_view_geometry(const record::Record& rec, const MeasureOptions& opt, const cv::Mat& lab, Measurement& out)
{
    ViewGeometry g;
    const ScaleCalibration* cal = opt.scale_calibration ? &*opt.scale_calibration : nullptr;
    if (cal && !rec.single_camera())
        throw ParameterError("a scale calibration photo (" + cal->photo + ") is for single photos; " + rec.specimen_id +
                             " is measured on its calibrated camera (cameras.top)");
    if (rec.single_camera()) {
        const auto& tp = *rec.top_photo;
        // A calibration photo of another size: said before any work on the photo.
        if (cal) check_calibration_size(*cal, rec.file(rec.top_image()).string(), out.top_image.cols, out.top_image.rows);
        // Nothing in the photo (one colour throughout): said at once, before
        // the disc search and GrabCut look for what is not there.
        if (const double spread = colour_spread(out.top_image); spread < kMinColourSpread)
            throw RefusalError({"no-cloth",
                                "no cloth found: " + rec.top_image() + " is one uniform colour (colour spread " + fmt("%.2f", spread) +
                                    " levels of 255): no drape, disc or background in it",
                                "photograph the drape on its stand (a lens cap, a blank or overexposed file shows nothing)"});
        cv::Mat rough;
        if (!(tp.disc_centre_px && tp.disc_radius_px)) rough = rough_cloth_mask(out.top_image);
        // A phone writes its lens into the photo: the focal length from the 35 mm
        // equivalent, +-5 % (rounded to a whole mm, and a crop of the frame the
        // camera reports changes it), unless the camera height or focal length is declared.
        if (!tp.focal_px && !tp.camera_height) {
            const ExifLens lens = exif_lens(rec.file(rec.top_image()));
            if (!lens.warning.empty()) out.warnings.push_back("top view: " + rec.top_image() + ": " + lens.warning + " (lens not read)");
            if (lens.focal_35mm_mm) {
                record::Record with_lens = rec;
                with_lens.top_photo->focal_px = focal_px_from_35mm(*lens.focal_35mm_mm, out.top_image.cols, out.top_image.rows);
                with_lens.top_photo->focal_px_sigma_rel = 0.05;
                with_lens.top_photo->focal_px_source = "photo's EXIF (" + fmt("%.0f", *lens.focal_35mm_mm) + " mm, 35 mm equivalent)";
                return solve_view(with_lens, out.top_image, lab, rough, cal);
            }
        }
        return solve_view(rec, out.top_image, lab, rough, cal);
    }
    const record::Camera& declared = rec.cameras.at("top");
    g.camera = declared;
    g.source_text = "full calibration (cameras.top, declared pose)";
    if (opt.calibrate && !rec.boards.empty()) {
        out.top_calibration = calibrate_camera(rec, "top", out.top_image);
        for (const auto& w : out.top_calibration->warnings) out.warnings.push_back(w);
        if (out.top_calibration->ok) {
            g.camera = out.top_calibration->measured;
            g.source_text = "full calibration (cameras.top), pose measured on " + std::to_string(out.top_calibration->boards_found.size()) +
                            " floor chessboard(s)";
        }
    }
    g.source = record::ScaleSource::Calibration;
    g.camera_height = g.camera.centre().z();
    g.camera_height_source = "calibration";
    g.centre_px = g.camera.project({0, 0, 0});
    g.centre_source = "calibration";
    g.scale_px_per_m = (g.camera.project({rec.R2, 0, 0}) - g.centre_px).norm() / rec.R2;
    return g;
}

/// The perspective model D is reported with (MeasureOptions::perspective), and why
/// (tv.perspective_reason).
std::string choose_perspective(const record::Record& rec, const MeasureOptions& opt, const ViewGeometry& g, TopView& tv)
{
    const bool single = rec.single_camera();
    std::string persp = opt.perspective;
    if (persp == "auto" && single) persp = rec.top_photo->perspective;
    if (persp == "calibration") {
        if (single)
            throw ParameterError("perspective 'calibration' needs a calibrated record (cameras.top); this photo's scale is from " +
                                 std::string(record::to_string(g.source)));
        persp = "hem";
        tv.perspective_reason = "asked for: the hanging-hem model on the calibrated camera";
    } else if (persp == "auto") {
        // The vertical projection (what a drapemeter's shadow and the lab's D are)
        // in either case: with an unknown camera height the hem is back-projected
        // from the assumed one, whose spread is in D's uncertainty. The disc-plane
        // value is low by construction (the hem hangs below the disc and looks
        // smaller), so its interval would not cover the vertical projection.
        persp = "hem";
        if (single && !g.camera_height_known) {
            tv.perspective_reason = "the camera height is not known (" + g.camera_height_source +
                                    "): the hem is back-projected from that height, its spread in D's uncertainty";
        } else {
            tv.perspective_reason = std::string("the camera height is known (") + g.camera_height_source +
                                    "): the hem is back-projected to where it hangs";
        }
    } else if (persp == "none" || persp == "disc-plane" || persp == "hem") {
        tv.perspective_reason = "asked for";
    } else {
        throw ParameterError("perspective '" + persp + "': expected none, disc-plane, hem, calibration or auto");
    }
    return persp;
}

/// The cloth's probability per pixel and the region it may be in.
struct Segmented {
    cv::Mat prob, gate, lightness;
    cv::Mat colour_cloth; ///< the colour cue alone (PhotoSegmentation::colour_cloth)
    bool photo = false; ///< segmented as a photo (GrabCut, thresholds, a mask), not by the lab's fabric colour
};

/// The single photo's own threshold and mask (top_photo) unless the options give one.
SegmentOverrides photo_overrides(const record::Record& rec, const MeasureOptions& opt)
{
    SegmentOverrides ov = opt.overrides;
    if (rec.single_camera() && ov.threshold.empty() && ov.mask.empty()) {
        ov.threshold = rec.top_photo->threshold;
        if (!rec.top_photo->mask.empty()) {
            const auto path = rec.file(rec.top_photo->mask);
            ov.mask = cv::imread(path.string(), cv::IMREAD_GRAYSCALE);
            if (ov.mask.empty()) throw FileError(path.string() + ": the mask named in top_photo.mask is not a readable image");
            ov.mask_name = rec.top_photo->mask;
        }
    }
    return ov;
}

/// Segments the top photo (tv.region and the segmentation's description); false,
/// with the reason in out.not_measured, when the lab's fabric colour cannot tell the
/// cloth from the floor or the cloth does not cover the disc.
bool segment_top(const record::Record& rec, const MeasureOptions& opt, const cv::Mat& lab, const record::Camera& cam, double angle,
                 Measurement& out, Segmented& s)
{
    TopView& tv = out.top;
    const std::string image_name = rec.top_image();
    const SegmentOverrides ov = photo_overrides(rec, opt);
    s.photo = (rec.single_camera() && opt.segmentation != "lab") || opt.segmentation == "photo" || !ov.threshold.empty() || !ov.mask.empty();
    const Eigen::Vector2d c0 = cam.project({0, 0, 0});
    if (s.photo) {
        PhotoSegmentation seg = segment_photo(out.top_image, lab, rec, cam, ov, angle);
        s.prob = seg.prob;
        s.gate = seg.gate;
        s.colour_cloth = seg.colour_cloth;
        tv.region = seg.region;
        tv.segmentation_method = seg.method;
        tv.photo_segmentation = true;
        tv.lightness_weight = seg.lightness_weight;
        tv.clamp_disc = seg.clamp_disc;
        tv.model.contrast = seg.contrast;
        tv.model.chromatic = seg.lightness_weight < 1;
        for (const auto& w : seg.warnings) tv.warnings.push_back("top view: " + w);
        return true;
    }
    tv.model = fabric_model(rec, cam, lab);
    tv.segmentation_method = tv.model.chromatic ? "fabric colour on the disc vs floor ring, by chroma"
                                                : "fabric colour on the disc vs floor ring, by darkness";
    if (tv.model.contrast < 8.0) {
        out.not_measured.push_back("top view: no fabric distinguishable from the floor in " + image_name + " (colour contrast " +
                                   fmt("%.1f", tv.model.contrast) + " Lab units < 8)");
        return false;
    }
    s.prob = fabric_probability(lab, tv.model);
    const double reach_px = (cam.project({rec.specimen.max_reach() + 0.02, 0, 0}) - c0).norm();
    s.gate = central_component(s.prob, c0, reach_px);
    tv.region = (s.prob >= 0.5f) & s.gate;
    // The fabric must at least cover the pedestal top; otherwise what sits on
    // the pedestal is not the specimen (or the photo has none).
    const double ped_px = (cam.project({rec.R2, 0, 0}) - c0).norm();
    cv::Mat disc = cv::Mat::zeros(s.prob.size(), CV_8U);
    cv::circle(disc, cv::Point(static_cast<int>(c0.x()), static_cast<int>(c0.y())), static_cast<int>(0.9 * ped_px), 255, cv::FILLED);
    const double covered = static_cast<double>(cv::countNonZero(s.gate & disc)) / std::max(1, cv::countNonZero(disc));
    if (covered < 0.9) {
        out.not_measured.push_back("top view: the support disc in " + image_name + " is not covered by fabric (" +
                                   fmt("%.0f", covered * 100) + " % of it): no specimen on the stand?");
        return false;
    }
    if (!tv.model.chromatic) cv::extractChannel(lab, s.lightness, 0);
    return true;
}

/// The outline under every perspective model: in the scale reference's plane, in
/// the disc-top plane and back-projected onto the hem's height model.
struct Traces {
    TraceSetup base, ref_setup, disc_setup, hem_setup;
    Trace ref, disc, hem;
};

/// The flat specimen's reach per ray at angle a (circle: its largest reach all round).
std::vector<double> reach_for(const record::Record& rec, int rays, double a, bool circle)
{
    record::Specimen sp = rec.specimen;
    sp.angle = a;
    const double rmax = sp.max_reach();
    std::vector<double> v(static_cast<std::size_t>(rays));
    for (int k = 0; k < rays; ++k) v[static_cast<std::size_t>(k)] = circle ? rmax : sp.reach(2 * M_PI * k / rays);
    return v;
}

Traces trace_models(const record::Record& rec, const MeasureOptions& opt, const ViewGeometry& g, const Segmented& s,
                    const record::ContourStack* stack, TopView& tv)
{
    const record::Camera& cam = g.camera;
    const bool round = rec.specimen.shape == record::Specimen::Shape::Round;
    const bool angle_known = round || !rec.specimen.angle_from_photo;
    double angle = rec.specimen.angle;
    Traces tr;
    tr.base.R2 = rec.R2;
    tr.base.H = g.camera_height;
    if (!angle_known) {
        TraceSetup t0 = tr.base;
        t0.model = HeightModel::Plane;
        t0.reach = reach_for(rec, opt.rays, 0, true);
        angle = estimate_angle(rec.specimen, trace_outline(cam, s.prob, s.gate, t0, s.lightness).outline);
    }
    tv.specimen_angle = angle;
    tr.base.reach = reach_for(rec, opt.rays, angle, false);
    for (const auto& q : search_limit_px(rec, cam, angle_known ? angle : kNaN)) tv.limit_px.emplace_back(q.x, q.y);

    tr.ref_setup = tr.disc_setup = tr.hem_setup = tr.base;
    tr.ref_setup.model = tr.disc_setup.model = HeightModel::Plane;
    tr.ref_setup.z_plane = rec.single_camera() ? g.reference_height : 0.0;
    tr.hem_setup.model = HeightModel::Chord;
    tr.ref = trace_outline(cam, s.prob, s.gate, tr.ref_setup, s.lightness);
    tr.disc = tr.ref_setup.z_plane == 0.0 ? tr.ref : trace_outline(cam, s.prob, s.gate, tr.disc_setup, s.lightness);
    tr.hem = trace_outline(cam, s.prob, s.gate, tr.hem_setup, s.lightness);
    if (stack && !stack->profiles.empty() && round) {
        TraceSetup tc = tr.base;
        tc.model = HeightModel::Contours;
        tc.stack = stack;
        const Trace cont = trace_outline(cam, s.prob, s.gate, tc, s.lightness);
        if (cont.outline.size() >= 8) tv.dc_contours_percent = dc_area(cont.outline, rec.R1, rec.R2).first;
    }
    return tr;
}

const char* const kSegmentationRemedy =
    "look at the overlay (--overlay), then give a threshold (--threshold L<NN, L>NN, a>NN, ...) or a mask image "
    "(--mask FILE.png: white = cloth, black = not, grey = let the segmentation decide)";

/// Refuses the photo, with the outline that was traced shown on the overlay.
[[noreturn]] void refuse(TopView& tv, const Trace& best, const std::string& check, const std::string& msg, const std::string& remedy)
{
    tv.outline_px = best.px;
    tv.at_limit_px = best.at_limit_px;
    tv.rays_at_limit = best.at_limit;
    throw RefusalError({check, msg, remedy});
}

/// What cannot be, before the outline is measured: a region that is the
/// background, runs off the photo, has too few edges, reaches the search limit or
/// lies beyond the flat specimen. Refuses (throws) on a single photo; false, with
/// the reason in out.not_measured, where a calibrated record may go on without its
/// top view.
bool outline_possible(const record::Record& rec, int rays, const Traces& tr, const Trace& best, bool photo_seg, Measurement& out)
{
    TopView& tv = out.top;
    const bool single = rec.single_camera();
    const std::string seg_remedy = kSegmentationRemedy;
    if (tv.region_image_fraction > 0.6)
        refuse(tv, best, "region-size",
               "the region counted as cloth covers " + fmt("%.0f", 100 * tv.region_image_fraction) +
                   " % of the photo: the background was taken for cloth",
               seg_remedy);
    if (touches_border(tv.region) && photo_seg)
        refuse(tv, best, "border",
               "the region counted as cloth touches the photo's border: the drape runs off the photo, or a "
               "shadow or the background joined it",
               "photograph the whole drape with a margin of background all round; otherwise " + seg_remedy);
    if (best.outline.size() < static_cast<std::size_t>(rays) * 9 / 10) {
        const std::string msg = "top view: fabric edge found on only " + std::to_string(best.outline.size()) + " of " +
                                std::to_string(rays) + " rays";
        if (single) refuse(tv, best, "edge-not-found", msg, seg_remedy);
        out.not_measured.push_back(msg);
        return false;
    }
    if (best.at_limit > std::max(3, rays / 50))
        refuse(tv, best, "search-limit",
               "on " + std::to_string(best.at_limit) + " of " + std::to_string(rays) +
                   " rays the cloth reaches the search limit (the flat specimen's edge + 5 %, where no " + rec.specimen.describe() +
                   " specimen can hang): a shadow or the background is counted as cloth, or the scale or specimen size is wrong",
               "check --disc / --specimen and the scale (the overlay shows the limit as a yellow line); otherwise " + seg_remedy);
    // A specimen cannot hang further out than its flat edge: where the outline in
    // the disc-top plane (which, seen from above, is never further out than the
    // hem really is) lies beyond it by more than 3 % + 3 mm (off-centring,
    // stretch), the region is not the specimen.
    int beyond = 0;
    std::vector<Eigen::Vector2d> where;
    for (std::size_t i = 0; i < tr.disc.outline.size(); ++i) {
        const Eigen::Vector2d& p = tr.disc.outline[i];
        double th = std::atan2(p.y(), p.x());
        if (th < 0) th += 2 * M_PI;
        const auto k = static_cast<std::size_t>(std::lround(th / (2 * M_PI) * rays)) % static_cast<std::size_t>(rays);
        if (p.norm() > 1.03 * tr.base.reach[k] + 0.003) {
            ++beyond;
            where.push_back(tr.disc.px[i]);
        }
    }
    if (beyond > rays / 20) {
        tv.outline_px = best.px;
        tv.at_limit_px = where;
        tv.rays_at_limit = beyond;
        throw RefusalError({"beyond-specimen",
                            "on " + std::to_string(beyond) + " of " + std::to_string(rays) +
                                " rays the counted region lies beyond the flat specimen's edge (" + rec.specimen.describe() +
                                "), where no cloth can hang: the specimen or disc size is wrong, the scale is wrong, or "
                                "something else (a shadow, the background) is counted as cloth",
                            "check --specimen, --disc and the scale (the overlay shows the flat specimen in grey); otherwise " +
                                seg_remedy});
    }
    return true;
}

/// What cannot be, once measured: nothing hanging over the disc, D outside 0..100 %.
bool drape_possible(const record::Record& rec, const record::Camera& cam, const Trace& best, Measurement& out)
{
    TopView& tv = out.top;
    const Eigen::Vector2d c0 = cam.project({0, 0, 0});
    double max_px = 0;
    for (const auto& u : best.px) max_px = std::max(max_px, (u - c0).norm());
    const double ped_px = (cam.project({rec.R2, 0, 0}) - c0).norm();
    const std::string seg_remedy = kSegmentationRemedy;
    if (max_px < ped_px + 3.0) {
        // Only the pedestal top was found (in the image, nothing reaches past
        // the disc's own edge): a specimen always hangs over the disc.
        const std::string msg = "top view: nothing hangs over the support disc in " + rec.top_image() + " (outline within " +
                                fmt("%.1f", max_px - ped_px) + " px of the disc edge): no specimen on the stand?";
        if (rec.single_camera()) refuse(tv, best, "no-drape", msg, "check --disc (the disc's diameter) and the scale; " + seg_remedy);
        out.not_measured.push_back(msg);
        return false;
    }
    const double D = tv.metrics.drape_coefficient_percent;
    if (!(D >= 0.0 && D <= 100.0))
        refuse(tv, best, "dc-range",
               "the drape coefficient would be " + fmt("%.1f", D) + " %, outside 0..100 %: the counted region is " +
                   (D > 100 ? "larger than the flat specimen" : "smaller than the disc"),
               "check --disc and --specimen (diameters, not radii) and the scale; otherwise " + seg_remedy);
    return true;
}

/// One perspective model's D with its uncertainty terms. Remaining error: (1) edge
/// placement, 0.5 px along the whole perimeter; (2) the scale reference (its own
/// error, its height); (3) the camera height (moves every height-corrected
/// radius); (4) the hem's height model: a height error dz scales every radius by
/// dz / (H - z), so dD = 2 A dz / (H - z) / (specimen area - disc area).
PerspectiveValue perspective_value(const record::Record& rec, const MeasureOptions& opt, const ViewGeometry& g, const Segmented& s,
                                   const Traces& tr, const Trace& t, const std::string& model, bool uses_ref_height, bool uses_H,
                                   TopView& tv)
{
    const int rays = opt.rays;
    const double Req = rec.R1, H = g.camera_height, z_ref = tr.ref_setup.z_plane;
    const double ring = rec.specimen.area() - M_PI * rec.R2 * rec.R2;
    PerspectiveValue v;
    v.model = model;
    v.available = t.outline.size() >= static_cast<std::size_t>(rays) * 9 / 10;
    if (!v.available) return v;
    const auto m = cloth::drape_metrics(t.outline, Req, rec.R2, opt.metrics);
    v.dc_percent = m.drape_coefficient_percent;
    v.area_m2 = m.shadow_area_m2;
    double zbar = 0;
    for (double z : t.z) zbar += z;
    zbar /= static_cast<double>(t.z.size());
    const double px_m = (H - zbar) / g.camera.fx; // one pixel at the outline [m]
    const double A = m.shadow_area_m2;
    v.terms.push_back({"edge", 2 * M_PI * m.mean_radius_m * 0.5 * px_m / ring * 100.0, "0.5 px along the outline"});
    if (rec.single_camera()) {
        v.terms.push_back({"scale", 2 * A / ring * g.scale_sigma_rel * 100.0, "scale reference +-" + fmt("%.2f", 100 * g.scale_sigma_rel) + " %"});
        if (uses_ref_height && g.reference_height_sigma > 0)
            v.terms.push_back({"scale_reference_height", 2 * A / ring * g.reference_height_sigma / (H - z_ref) * 100.0,
                               "reference height +-" + fmt("%.1f", 1e3 * g.reference_height_sigma) + " mm"});
        if (uses_H && g.camera_height_sigma > 0) {
            const double Hp = H + g.camera_height_sigma, Hm = std::max(H - g.camera_height_sigma, z_ref + 0.3 * (H - z_ref));
            TraceSetup ts = model == "hem" ? tr.hem_setup : tr.disc_setup;
            double d[2];
            int i = 0;
            for (double Hx : {Hp, Hm}) {
                ts.H = Hx;
                const Trace tx = trace_outline(camera_with_height(g, Hx), s.prob, s.gate, ts, s.lightness);
                d[i++] = tx.outline.size() >= static_cast<std::size_t>(rays) / 2 ? dc_area(tx.outline, Req, rec.R2).first : v.dc_percent;
            }
            v.terms.push_back({"camera_height", 0.5 * std::abs(d[0] - d[1]),
                               "camera height " + fmt("%.0f", 1e3 * H) + " +-" + fmt("%.0f", 1e3 * g.camera_height_sigma) + " mm (" +
                                   (g.camera_height_known ? "known" : "assumed") + ")"});
        }
        // The centroid fallback's centre: D traced again with the centre moved by
        // its RMS reach per axis (centre_sigma / sqrt 2) either way, the larger
        // change per axis (a centre off in any direction may lower D).
        if (uses_H && std::isfinite(g.centre_sigma) && g.centre_sigma > 0) {
            const Eigen::Vector2d c0 = g.camera.project({0, 0, 0});
            const double px_per_m = (g.camera.project({rec.R2, 0, 0}) - c0).norm() / rec.R2;
            const double step = g.centre_sigma / std::sqrt(2.0) * px_per_m;
            TraceSetup ts = model == "hem" ? tr.hem_setup : tr.disc_setup;
            double ss_c = 0;
            for (const Eigen::Vector2d& axis : {Eigen::Vector2d(1, 0), Eigen::Vector2d(0, 1)}) {
                double worst = 0;
                for (double sign : {1.0, -1.0}) {
                    ViewGeometry moved = g;
                    moved.centre_px += sign * step * axis;
                    const Trace tx = trace_outline(camera_with_height(moved, H), s.prob, s.gate, ts, s.lightness);
                    if (tx.outline.size() >= static_cast<std::size_t>(rays) / 2)
                        worst = std::max(worst, std::abs(dc_area(tx.outline, Req, rec.R2).first - v.dc_percent));
                }
                ss_c += worst * worst;
            }
            v.terms.push_back({"disc_centre", std::sqrt(ss_c),
                               "disc centre (the cloth's centroid) within " + fmt("%.0f", 1e3 * g.centre_bound) + " mm, " +
                                   fmt("%.0f", 1e3 * g.centre_sigma) + " mm RMS"});
        }
    }
    if (model == "hem") {
        tv.dc_per_metre_height = 2 * A / (H - zbar) / ring * 100.0;
        v.terms.push_back({"hem_depth", tv.dc_per_metre_height * 0.010, "the hem's height model +-10 mm"});
    }
    sum_terms(v);
    return v;
}

/// A single photo's outline against the colours either side of it (GrabCut's
/// region is a guess where the cloth meets a background of nearly its colour: a
/// soft shadow it followed, or a lit face it left out - or, as often, a right
/// outline along shaded folds as light as the floor). Where inside and outside
/// hardly differ on more than half of the outline, the photo is refused
/// (`weak-outline`); on fewer rays, D's uncertainty gets half the change of D when
/// the weak rays lie out at the strong rays' largest radius or in at their smallest.
void check_outline_edges(const record::Record& rec, const cv::Mat& lab, const cv::Mat& colour_cloth, const record::Camera& cam,
                         const Trace& best, double wL, TopView& tv)
{
    const std::size_t n = best.px.size();
    if (n < 8 || best.outline.size() != n) return;
    const Eigen::Vector2d c0 = cam.project({0, 0, 0});
    std::vector<double> contrast(n);
    std::vector<char> cue_disagrees(n, 0);
    auto cloth_cue = [&](const Eigen::Vector2d& q) {
        const int x = std::clamp(static_cast<int>(std::lround(q.x())), 0, colour_cloth.cols - 1);
        const int y = std::clamp(static_cast<int>(std::lround(q.y())), 0, colour_cloth.rows - 1);
        return colour_cloth.at<uchar>(y, x) != 0;
    };
    for (std::size_t k = 0; k < n; ++k) {
        const Eigen::Vector2d p = best.px[k];
        const Eigen::Vector2d dir = (p - c0).normalized();
        cv::Vec3f in(0, 0, 0), out(0, 0, 0);
        int in_cloth = 0, out_cloth = 0;
        for (int s = 2; s <= 8; ++s) {
            in += sample(lab, p - s * dir);
            out += sample(lab, p + s * dir);
            if (!colour_cloth.empty()) {
                in_cloth += cloth_cue(p - s * dir);
                out_cloth += cloth_cue(p + s * dir);
            }
        }
        // The colour cue alone says the outline is inside the cloth (cloth's colours
        // beyond it) or around the background (the background's colours within it).
        if (!colour_cloth.empty() && (out_cloth >= 4 || in_cloth <= 3)) cue_disagrees[k] = 1;
        const cv::Vec3f d = (in - out) / 7.0f;
        contrast[k] = std::sqrt(wL * wL * d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    }
    const double med = median(contrast);
    const double weak_below = std::max(3.0, 0.3 * med);
    std::vector<char> weak(n, 0);
    std::size_t n_weak = 0;
    for (std::size_t k = 0; k < n; ++k)
        if (contrast[k] < weak_below || cue_disagrees[k]) {
            weak[k] = 1;
            ++n_weak;
        }
    tv.outline_edge_contrast = med;
    tv.weak_outline_fraction = static_cast<double>(n_weak) / static_cast<double>(n);
    if (n_weak == 0) return;
    auto angle_deg = [&](std::size_t k) {
        double a = std::atan2(best.outline[k].y(), best.outline[k].x()) * 180 / M_PI;
        return a < 0 ? a + 360 : a;
    };
    // The longest run of weak rays (around the circle), for the message.
    std::size_t best_start = 0, best_len = 0;
    for (std::size_t k = 0; k < n; ++k) {
        if (!weak[k] || weak[(k + n - 1) % n]) continue;
        std::size_t len = 0;
        while (len < n && weak[(k + len) % n]) ++len;
        if (len > best_len) {
            best_len = len;
            best_start = k;
        }
    }
    if (best_len == 0) best_len = n; // every ray weak
    if (tv.weak_outline_fraction > 0.5)
        refuse(tv, best, "weak-outline",
               "on " + fmt("%.0f", 100 * tv.weak_outline_fraction) + " % of the outline (the longest stretch from " +
                   fmt("%.0f", angle_deg(best_start)) + " to " + fmt("%.0f", angle_deg((best_start + best_len - 1) % n)) +
                   " deg) the colours either side of it differ by less than " + fmt("%.1f", weak_below) + " L*a*b* units (" +
                   fmt("%.1f", med) + " along the rest): there the outline follows a soft shadow or cuts through the cloth, "
                   "not the cloth's edge",
               "look at the overlay (--overlay); photograph without the rig's shadow, on a background unlike every face of the "
               "cloth; or give a threshold (--threshold L<NN, ...) or a mask (--mask FILE.png)");
    // Where the edge is weak the hem may lie anywhere the strong rays' hem lies:
    // D with the weak rays out at the strong rays' largest radius, and in at their
    // smallest; half the larger change is the term (a cut-away face lowers D, a
    // shadow joined to the cloth raises it).
    double r_lo = 1e9, r_hi = 0;
    for (std::size_t k = 0; k < n; ++k)
        if (!weak[k]) {
            r_lo = std::min(r_lo, best.outline[k].norm());
            r_hi = std::max(r_hi, best.outline[k].norm());
        }
    if (!(r_hi > 0)) r_lo = r_hi = rec.R2;
    cloth::Polygon2 out_poly = best.outline, in_poly = best.outline;
    for (std::size_t k = 0; k < n; ++k) {
        if (!weak[k]) continue;
        const double r = best.outline[k].norm();
        out_poly[k] = best.outline[k].normalized() * std::max(r, r_hi);
        in_poly[k] = best.outline[k].normalized() * std::max(std::min(r, r_lo), rec.R2);
    }
    const double d_best = dc_area(best.outline, rec.R1, rec.R2).first;
    const double term = 0.5 * std::max(dc_area(out_poly, rec.R1, rec.R2).first - d_best, d_best - dc_area(in_poly, rec.R1, rec.R2).first);
    for (PerspectiveValue* v : {&tv.uncorrected, &tv.disc_plane, &tv.hem}) {
        if (!v->available) continue;
        v->terms.push_back({"weak_outline", term,
                            fmt("%.1f", 100 * tv.weak_outline_fraction) + " % of the outline on a weak colour edge (below " +
                                fmt("%.1f", weak_below) + " L*a*b* units): half of D's change with those rays at the others' "
                                "largest or smallest radius"});
        sum_terms(*v);
    }
    set_reported_uncertainty(tv);
    tv.warnings.push_back("top view: " + fmt("%.1f", 100 * tv.weak_outline_fraction) +
                          " % of the outline lies on a weak colour edge: D's uncertainty carries it (weak_outline " + fmt("%.2f", term) +
                          " points)");
}

/// Every perspective model's D and uncertainty; the edge term of the chosen one.
void set_perspective_values(const record::Record& rec, const MeasureOptions& opt, const ViewGeometry& g, const Segmented& s, const Traces& tr,
                            TopView& tv)
{
    const bool single = rec.single_camera();
    tv.uncorrected = perspective_value(rec, opt, g, s, tr, tr.ref, "none", false, false, tv);
    tv.uncorrected.meaning = single ? "outline in the scale reference's plane (z = " + fmt("%.0f", 1e3 * tr.ref_setup.z_plane) +
                                          " mm), no height correction: what a ruler on the photo gives"
                                    : "outline in the disc-top plane z = 0, no height correction";
    tv.disc_plane = tr.ref_setup.z_plane == 0.0 ? tv.uncorrected : perspective_value(rec, opt, g, s, tr, tr.disc, "disc-plane", true, true, tv);
    tv.disc_plane.model = "disc-plane";
    tv.disc_plane.meaning = "outline back-projected onto the disc-top plane: low by about hem depth / camera height "
                            "(the hem hangs below the disc and looks smaller)";
    tv.hem = perspective_value(rec, opt, g, s, tr, tr.hem, "hem", true, true, tv);
    tv.hem.meaning = "the hem back-projected onto a straight inextensible fibre from the disc edge (the vertical projection, "
                     "as a drapemeter's shadow)";
    const double hem_edge = tv.hem.terms.empty() ? 0.0 : tv.hem.terms.front().points;
    tv.dc_edge_term = hem_edge;
    set_hem_depth_error(tv, 0.010);
    if (tv.perspective == "hem" && tv.hem.available) tv.dc_edge_term = hem_edge;
    else if (tv.perspective == "disc-plane") tv.dc_edge_term = tv.disc_plane.terms.front().points;
    else tv.dc_edge_term = tv.uncorrected.terms.front().points;
}

/// What a person should know about a measured top view.
void top_warnings(const record::Record& rec, const MeasureOptions& opt, const ViewGeometry& g, const Trace& best, bool photo_seg, TopView& tv)
{
    const int rays = opt.rays;
    if (best.beyond > rays / 20)
        tv.warnings.push_back("top view: on " + std::to_string(best.beyond) +
                              " rays the fabric edge lies beyond the height model's hem (shadow or segmentation spill?)");
    if (!photo_seg && !tv.model.chromatic && tv.model.contrast < 25)
        tv.warnings.push_back("top view: grey fabric with low contrast to the floor (" + fmt("%.0f", tv.model.contrast) +
                              " L* units); the edge may include the contact shadow");
    if (rec.single_camera() && tv.perspective == "disc-plane" && tv.hem.available)
        tv.warnings.push_back("top view: D is given in the disc-top plane (" + fmt("%.1f", tv.disc_plane.dc_percent) +
                              " %); the hem model would give " + fmt("%.1f", tv.hem.dc_percent) + " +- " +
                              fmt("%.1f", tv.hem.uncertainty_percent) + " % with the camera height " + g.camera_height_source);
}

} // namespace

void detail::measure_top(const record::Record& rec, const MeasureOptions& opt, const record::ContourStack* stack, Measurement& out)
{
    TopView& tv = out.top;
    const cv::Mat lab = to_lab(out.top_image);
    const double Req = rec.R1; // equal-area radius: D = (A - disc) / (specimen - disc) for any shape
    ViewGeometry g = top_view_geometry(rec, opt, lab, out);
    for (const auto& w : g.warnings) out.warnings.push_back("top view: " + w);
    out.view = g;
    const record::Camera& cam = g.camera;
    tv.perspective = choose_perspective(rec, opt, g, tv);
    const bool round = rec.specimen.shape == record::Specimen::Shape::Round;
    const bool angle_known = round || !rec.specimen.angle_from_photo;
    Segmented s;
    if (!segment_top(rec, opt, lab, cam, angle_known ? rec.specimen.angle : kNaN, out, s)) return;
    tv.region_image_fraction = static_cast<double>(cv::countNonZero(tv.region)) / static_cast<double>(tv.region.total());
    if (const std::string w = bound_disc_centre(rec, tv.region, g); !w.empty()) {
        out.warnings.push_back("top view: " + w);
        out.view = g;
    }
    const Traces tr = trace_models(rec, opt, g, s, stack, tv);
    const std::string& persp = tv.perspective;
    const Trace& best = persp == "hem" ? tr.hem : persp == "disc-plane" ? tr.disc : tr.ref;
    tv.height_model = persp == "hem" ? HeightModel::Chord : HeightModel::Plane;
    if (!outline_possible(rec, opt.rays, tr, best, s.photo, out)) return;
    tv.dc_plane_percent = dc_area(tr.disc.outline, Req, rec.R2).first;
    tv.dc_chord_percent = dc_area(tr.hem.outline, Req, rec.R2).first;
    tv.outline = best.outline;
    tv.outline_z = best.z;
    tv.outline_arc = best.arc;
    tv.outline_px = best.px;
    tv.rays_beyond_reach = best.beyond;
    tv.rays_at_limit = best.at_limit;
    tv.at_limit_px = best.at_limit_px;
    tv.metrics = cloth::drape_metrics(tv.outline, Req, rec.R2, opt.metrics);
    if (!drape_possible(rec, cam, best, out)) return;
    set_perspective_values(rec, opt, g, s, tr, tv);
    if (s.photo && rec.single_camera() && tv.segmentation_method.rfind("GrabCut", 0) == 0)
        check_outline_edges(rec, lab, s.colour_cloth, cam, best, tv.lightness_weight, tv);
    top_warnings(rec, opt, g, best, s.photo, tv);
    tv.measured = true;
    out.measured.push_back("top view: drape coefficient, nodes, r(theta)");
}

/// Front hem seen against the pedestal in the side view.
} // namespace drape::capture
