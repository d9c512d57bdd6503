#include "engine/capture/report.hpp"

#include "engine/capture/pixels.hpp"
#include "engine/core/error.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace drape::capture {

using namespace detail;

using json = nlohmann::ordered_json;

namespace {

nlohmann::ordered_json num(double v)
{
    return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr);
}

} // namespace

namespace {

/// The top view's measurement in detail (the "top" block).
json top_json(const TopView& t)
{
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
    top["rays_at_search_limit"] = t.rays_at_limit;
    top["region_image_fraction"] = t.region_image_fraction;
    top["outline_edge_contrast_lab"] = num(t.outline_edge_contrast);
    top["weak_outline_fraction"] = num(t.weak_outline_fraction);
    top["specimen_angle_deg"] = t.specimen_angle * 180.0 / M_PI;
    top["height_error_m"] = t.height_error_m;
    top["drape_coefficient_edge_error_percent"] = t.dc_edge_term;
    if (t.photo_segmentation)
        top["segmentation"] = {{"method", t.segmentation_method},
                               {"contrast_lab", t.model.contrast},
                               {"lightness_weight", t.lightness_weight},
                               {"upper_disc", t.clamp_disc}};
    else
        top["segmentation"] = {{"method", t.segmentation_method},
                               {"by", t.model.chromatic ? "chroma" : "darkness"},
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
    return top;
}

/// Each perspective model's D with its uncertainty and terms.
json perspective_models_json(const TopView& t)
{
    json models = json::object();
    for (const PerspectiveValue* v : {&t.uncorrected, &t.disc_plane, &t.hem}) {
        json terms = json::array();
        for (const auto& term : v->terms)
            terms.push_back({{"name", term.name}, {"points_percent", term.points}, {"note", term.note}});
        models[v->model] = {{"available", v->available},
                            {"drape_coefficient_percent", num(v->dc_percent)},
                            {"uncertainty_percent", num(v->uncertainty_percent)},
                            {"shadow_area_m2", num(v->area_m2)},
                            {"uncertainty_terms", terms},
                            {"meaning", v->meaning}};
    }
    return models;
}

/// Where the scale came from, and the disc rim, markers and chessboard it found.
json scale_json(const ViewGeometry& g)
{
    json sc = {{"source", record::to_string(g.source)},
               {"description", g.source_text},
               {"single_camera", g.single_camera},
               {"reference_height_m", g.reference_height},
               {"reference_height_sigma_m", g.reference_height_sigma},
               {"px_per_m", g.scale_px_per_m},
               {"scale_sigma_relative", g.scale_sigma_rel},
               {"camera_height_m", g.camera_height},
               {"camera_height_sigma_m", g.camera_height_sigma},
               {"camera_height_known", g.camera_height_known},
               {"camera_height_source", g.camera_height_source},
               {"disc_centre_px", {g.centre_px.x(), g.centre_px.y()}},
               {"disc_centre_source", g.centre_source},
               {"disc_centre_bound_m", num(g.centre_bound)},
               {"disc_centre_sigma_m", num(g.centre_sigma)}};
    if (g.disc)
        sc["disc_rim"] = {{"centre_px", {g.disc->centre_px.x(), g.disc->centre_px.y()}},
                          {"radius_px", g.disc->radius_px},
                          {"axis_ratio", g.disc->axis_ratio},
                          {"ray_fraction", g.disc->ray_fraction},
                          {"rms_px", g.disc->rms_px},
                          {"edge", g.disc->edge},
                          {"declared", g.disc->declared}};
    if (!g.markers.empty()) {
        json mk = json::array();
        for (const auto& mm : g.markers) mk.push_back(mm.id);
        sc["markers_found"] = mk;
    }
    if (!g.board_corners_px.empty()) sc["chessboard_corners"] = g.board_corners_px.size();
    sc["calibration_photo"] = g.calibration_photo.empty() ? json(nullptr) : json(g.calibration_photo);
    return sc;
}

/// The laser contours per depth.
json contours_json(const std::vector<ContourLevel>& contours)
{
    json cs = json::array();
    for (const auto& c : contours) {
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
    return cs;
}

} // namespace

nlohmann::ordered_json to_json(const Measurement& m)
{
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
        top_block = top_json(t);
    } else {
        j["drape_coefficient_percent"] = nullptr;
        j["node_count"] = nullptr;
        j["node_angles_deg"] = nullptr;
    }
    if (t.measured) {
        j["drape_coefficient_uncorrected_percent"] = num(t.uncorrected.dc_percent);
        j["perspective"] = t.perspective;
        j["perspective_reason"] = t.perspective_reason;
    }
    j["refused"] = m.refused ? json{{"check", m.refused->check}, {"message", m.refused->message}, {"remedy", m.refused->remedy}}
                             : json(nullptr);
    if (t.measured) j["perspective_models"] = perspective_models_json(t);
    if (m.view) j["scale"] = scale_json(*m.view);
    j["hem_min_height_m"] = m.hem_min_height ? json(*m.hem_min_height) : json(nullptr);
    j["hem_min_height_source"] = m.hem_min_source;
    j["free_strip_bending_bound_Nm"] = m.free_strip_bending_bound ? json(*m.free_strip_bending_bound) : json(nullptr);
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
    if (m.side.pedestal.measured)
        j["pedestal"] = {{"diameter_m", m.side.pedestal.diameter},
                         {"diameter_sigma_m", m.side.pedestal.diameter_sigma},
                         {"declared_diameter_m", m.side.pedestal.declared},
                         {"rows", m.side.pedestal.rows},
                         {"differs_from_declared", m.side.pedestal.differs},
                         {"source", "side photo: the silhouette's edges below the cloth"}};
    if (m.side.measured)
        j["side"] = {{"columns", m.side.columns},
                     {"hem_min_height_m", m.side.hem_min_z},
                     {"hem_min_theta_deg", m.side.hem_min_theta * 180.0 / M_PI},
                     {"drape_depth_m", -m.side.hem_min_z},
                     {"rms_diff_to_top_height_model_m", num(m.side.model_rms_diff)}};
    j["contours"] = contours_json(m.contours);
    j["measured"] = m.measured;
    j["not_measured"] = m.not_measured;
    j["bad_files"] = m.bad_files;
    j["warnings"] = m.warnings;
    return j;
}

namespace {

using Lines = std::vector<std::pair<std::string, cv::Scalar>>;

/// Appends `msg` wrapped at `width` characters, up to six lines in all.
void append_wrapped(Lines& lines, std::string msg, std::size_t width, const cv::Scalar& col)
{
    while (!msg.empty() && lines.size() < 6) {
        std::size_t cut = msg.size() <= width ? msg.size() : msg.rfind(' ', width);
        if (cut == std::string::npos || cut == 0) cut = std::min(width, msg.size());
        lines.emplace_back(msg.substr(0, cut), col);
        msg = cut < msg.size() ? msg.substr(cut + 1) : "";
    }
}

/// `body` under a banner of `lines` (the first larger and bold).
cv::Mat with_banner(const cv::Mat& body, const Lines& lines)
{
    const int line_h = 22, banner = 10 + line_h * static_cast<int>(lines.size());
    cv::Mat img(body.rows + banner, body.cols, CV_8UC3, cv::Scalar(255, 255, 255));
    body.copyTo(img(cv::Rect(0, banner, body.cols, body.rows)));
    for (std::size_t i = 0; i < lines.size(); ++i)
        cv::putText(img, lines[i].first, {8, 24 + line_h * static_cast<int>(i)}, cv::FONT_HERSHEY_SIMPLEX, i == 0 ? 0.62 : 0.5,
                    lines[i].second, i == 0 ? 2 : 1, cv::LINE_AA);
    return img;
}

/// A photo refused before a camera existed (no scale reference found): the photo and why.
cv::Mat refused_photo(const Measurement& m)
{
    const double z = std::min(1.0, 1000.0 / std::max(m.top_image.cols, m.top_image.rows));
    cv::Mat body;
    cv::resize(m.top_image, body, {}, z, z, cv::INTER_AREA);
    const cv::Scalar red(0, 0, 200);
    Lines lines{{m.specimen_id + ": REFUSED" + (m.refused ? " (" + m.refused->check + ")" : std::string()) + ", no drape coefficient", red}};
    append_wrapped(lines, m.refused ? m.refused->message : std::string("top view not measured"),
                   static_cast<std::size_t>(std::max(40.0, body.cols / 9.5)), red);
    return with_banner(body, lines);
}

/// The part of the photo the overlay shows: the specimen's reach (and the search
/// limit, the markers on a single photo).
cv::Rect overlay_roi(const record::Record& rec, const Measurement& m, const record::Camera& cam, bool single)
{
    const auto& t = m.top;
    const Eigen::Vector2d c0 = cam.project({0, 0, 0});
    const double max_reach = rec.specimen.max_reach();
    cv::Rect roi;
    if (!single) {
        const double reach = (cam.project({max_reach * 1.12, 0, 0}) - c0).norm();
        roi = cv::Rect(static_cast<int>(c0.x() - reach), static_cast<int>(c0.y() - reach), static_cast<int>(2 * reach),
                       static_cast<int>(2 * reach));
    } else {
        std::vector<cv::Point> pts;
        for (const auto& p : t.limit_px) pts.emplace_back(static_cast<int>(p.x()), static_cast<int>(p.y()));
        for (int k = 0; k < 72 && pts.empty(); ++k) {
            const double a = 2 * M_PI * k / 72;
            const auto u = cam.project({1.1 * max_reach * std::cos(a), 1.1 * max_reach * std::sin(a), 0.0});
            pts.emplace_back(static_cast<int>(u.x()), static_cast<int>(u.y()));
        }
        for (const auto& mk : m.view->markers)
            for (const auto& q : mk.corners_px) pts.emplace_back(static_cast<int>(q.x()), static_cast<int>(q.y()));
        roi = cv::boundingRect(pts);
        const int pad = static_cast<int>(0.06 * std::max(roi.width, roi.height));
        roi -= cv::Point(pad, pad);
        roi += cv::Size(2 * pad, 2 * pad);
    }
    roi &= cv::Rect(0, 0, m.top_image.cols, m.top_image.rows);
    if (roi.width < 8 || roi.height < 8) roi = cv::Rect(0, 0, m.top_image.cols, m.top_image.rows);
    return roi;
}

/// What was counted: the rest of the photo faded towards white; a refused region
/// tinted red.
void fade_uncounted(cv::Mat& photo, const cv::Mat& region, bool refused)
{
    for (int y = 0; y < photo.rows; ++y)
        for (int x = 0; x < photo.cols; ++x) {
            cv::Vec3b& v = photo.at<cv::Vec3b>(y, x);
            if (!region.at<uchar>(y, x)) {
                for (int c = 0; c < 3; ++c) v[c] = cv::saturate_cast<uchar>(0.45 * v[c] + 0.55 * 255);
            } else if (refused) {
                const double tint[3] = {40, 40, 255};
                for (int c = 0; c < 3; ++c) v[c] = cv::saturate_cast<uchar>(0.6 * v[c] + 0.4 * tint[c]);
            }
        }
}

/// The enlarged crop of the photo and the projection of photo pixels and world
/// points onto it (sub-pixel drawing: coordinates * 4).
struct OverlayCanvas {
    cv::Mat body;
    cv::Rect roi;
    double zoom;
    const record::Camera& cam;
    static constexpr int shift = 2;
    cv::Point P(const Eigen::Vector2d& p) const
    {
        return cv::Point(static_cast<int>(std::lround(((p.x() - roi.x + 0.5) * zoom - 0.5) * (1 << shift))),
                         static_cast<int>(std::lround(((p.y() - roi.y + 0.5) * zoom - 0.5) * (1 << shift))));
    }
    cv::Point Pi(const Eigen::Vector2d& p) const
    {
        const cv::Point q = P(p);
        return cv::Point(q.x >> shift, q.y >> shift);
    }
    void polyline(const std::vector<Eigen::Vector2d>& px, const cv::Scalar& col, int thick)
    {
        std::vector<cv::Point> pts;
        for (const auto& p : px) pts.push_back(P(p));
        cv::polylines(body, pts, true, col, thick, cv::LINE_AA, shift);
    }
    template <class Radius> void curve_world(Radius radius, double z, const cv::Scalar& col, int thick)
    {
        std::vector<cv::Point> pts;
        for (int k = 0; k < 720; ++k) {
            const double a = 2 * M_PI * k / 720;
            const double r = radius(a);
            pts.push_back(P(cam.project({r * std::cos(a), r * std::sin(a), z})));
        }
        cv::polylines(body, pts, true, col, thick, cv::LINE_AA, shift);
    }
};

/// The folds: a tick from the pedestal edge out to each crest, numbered.
void draw_nodes(OverlayCanvas& canvas, const record::Record& rec, const TopView& t)
{
    const Eigen::Vector2d c0 = canvas.cam.project({0, 0, 0});
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
        const Eigen::Vector2d e = canvas.cam.project({rec.R2 * std::cos(a), rec.R2 * std::sin(a), 0.0});
        cv::line(canvas.body, canvas.P(e), canvas.P(p), cv::Scalar(0, 190, 255), 1, cv::LINE_AA, OverlayCanvas::shift);
        cv::circle(canvas.body, canvas.Pi(p), 7, cv::Scalar(0, 190, 255), 2, cv::LINE_AA);
        const Eigen::Vector2d lab = p + (p - c0).normalized() * 12.0 / canvas.zoom * 2.0;
        cv::putText(canvas.body, std::to_string(i + 1), canvas.Pi(lab) + cv::Point(-6, 6), cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(0, 90, 230), 2,
                    cv::LINE_AA);
    }
}

/// The banner: what was measured, how, or why not, wrapped to the picture's width.
Lines overlay_banner(const Measurement& m, bool single, int cols)
{
    const auto& t = m.top;
    Lines lines;
    const cv::Scalar black(0, 0, 0), red(0, 0, 200), grey(90, 90, 90);
    if (t.measured) {
        char buf[240];
        std::snprintf(buf, sizeof buf, "%s  D = %.1f %% +-%.1f (%s)  nodes %d", m.specimen_id.c_str(),
                      t.metrics.drape_coefficient_percent, t.dc_uncertainty_percent, t.perspective.c_str(), t.metrics.node_count);
        std::string text = buf;
        if (m.lab_dc_percent) text += "  (lab " + fmt("%.1f%%", *m.lab_dc_percent) + ")";
        lines.emplace_back(text, black);
        std::string models = "uncorrected " + fmt("%.1f", t.uncorrected.dc_percent);
        if (t.disc_plane.available && single) models += "   disc-plane " + fmt("%.1f", t.disc_plane.dc_percent);
        if (t.hem.available)
            models += "   hem " + fmt("%.1f", t.hem.dc_percent) + " +-" + fmt("%.1f", t.hem.uncertainty_percent);
        lines.emplace_back(models, grey);
    } else if (m.refused) {
        lines.emplace_back(m.specimen_id + ": REFUSED (" + m.refused->check + "), no drape coefficient", red);
        append_wrapped(lines, m.refused->message, static_cast<std::size_t>(std::max(40.0, cols / 9.5)), red);
    } else {
        lines.emplace_back(m.specimen_id + ": top view not measured", red);
    }
    if (m.view && single) lines.emplace_back("scale: " + m.view->source_text, grey);
    // Wrap long lines to the picture's width.
    const std::size_t width = static_cast<std::size_t>(std::max(40.0, cols / 9.0));
    Lines wrapped;
    for (auto [text, col] : lines) {
        const std::size_t w = wrapped.empty() ? static_cast<std::size_t>(width * 0.8) : width;
        while (text.size() > w) {
            std::size_t cut = text.rfind(' ', w);
            if (cut == std::string::npos || cut == 0) cut = w;
            wrapped.emplace_back(text.substr(0, cut), col);
            text = "  " + text.substr(cut + 1);
        }
        wrapped.emplace_back(text, col);
    }
    return wrapped;
}

} // namespace

cv::Mat draw_top_overlay(const record::Record& rec, const Measurement& m)
{
    if (m.top_image.empty()) throw ParameterError("draw_top_overlay: the record has no readable top photo");
    if (!m.view && !rec.has_camera("top")) return refused_photo(m);
    const record::Camera cam = m.view ? m.view->camera
                                      : (m.top_calibration && m.top_calibration->ok ? m.top_calibration->measured : rec.cameras.at("top"));
    const auto& t = m.top;
    const bool single = m.view && m.view->single_camera;
    // Cropped to the specimen's reach, enlarged so a person can judge the traced
    // edge to a fraction of a pixel.
    const cv::Rect roi = overlay_roi(rec, m, cam, single);
    const double zoom = single ? std::clamp(1000.0 / std::max(roi.width, roi.height), 0.25, 2.0) : 2.0;
    cv::Mat photo = m.top_image(roi).clone();
    if (!t.region.empty()) fade_uncounted(photo, t.region(roi), m.refused.has_value());
    OverlayCanvas c{cv::Mat(), roi, zoom, cam};
    cv::resize(photo, c.body, {}, zoom, zoom, zoom >= 1 ? cv::INTER_CUBIC : cv::INTER_AREA);
    record::Specimen sp = rec.specimen;
    sp.angle = t.specimen_angle;
    if (!t.limit_px.empty() && (single || m.refused)) c.polyline(t.limit_px, cv::Scalar(0, 220, 255), 1); // search limit (yellow)
    c.curve_world([&](double) { return rec.R2; }, 0.0, cv::Scalar(255, 255, 0), 1);          // disc edge (cyan)
    c.curve_world([&](double a) { return sp.reach(a); }, 0.0, cv::Scalar(150, 150, 150), 1); // flat specimen
    if (m.view) {
        for (const auto& mk : m.view->markers) {
            c.polyline(mk.corners_px, cv::Scalar(255, 0, 255), 2);
            cv::putText(c.body, std::to_string(mk.id), c.Pi(mk.corners_px[0]) + cv::Point(3, -4), cv::FONT_HERSHEY_SIMPLEX, 0.5,
                        cv::Scalar(255, 0, 255), 1, cv::LINE_AA);
        }
        for (const auto& p : m.view->board_corners_px) cv::circle(c.body, c.Pi(p), 3, cv::Scalar(255, 0, 255), 1, cv::LINE_AA);
    }
    if (!t.outline_px.empty()) c.polyline(t.outline_px, m.refused ? cv::Scalar(0, 0, 230) : cv::Scalar(0, 230, 0), 1);
    for (const auto& p : t.at_limit_px) cv::circle(c.body, c.Pi(p), 3, cv::Scalar(0, 0, 255), cv::FILLED, cv::LINE_AA);
    if (t.measured) draw_nodes(c, rec, t);
    return with_banner(c.body, overlay_banner(m, single, c.body.cols));
}

} // namespace drape::capture
