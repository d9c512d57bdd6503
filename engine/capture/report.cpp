#include "engine/capture/report.hpp"

#include "engine/capture/pixels.hpp"
#include "engine/core/error.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace drape::capture {

using namespace detail;

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

} // namespace drape::capture
