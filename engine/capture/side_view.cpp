#include "engine/capture/side_view.hpp"

#include "engine/capture/pixels.hpp"
#include "engine/capture/steps.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace drape::capture {

using namespace detail;

void detail::measure_side(const record::Record& rec, Measurement& out)
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

void detail::measure_pedestal(const record::Record& rec, Measurement& out)
{
    PedestalWidth& pw = out.side.pedestal;
    pw.declared = 2 * rec.R2;
    if (!rec.has_camera("side") || out.side_image.empty() || !(rec.R2 > 0) || !(rec.pedestal_height > 0)) return;
    const record::Camera& cam = rec.cameras.at("side");
    const Eigen::Vector3d o = cam.centre();
    const Eigen::Vector2d oxy(o.x(), o.y());
    const double dist = oxy.norm();
    if (!(dist > 2 * rec.R2)) return; // the camera stands outside the pedestal, or the edges are not a silhouette
    // Luminance, smoothed along the columns (5 rows) against the pedestal's
    // texture and along the rows by a Gaussian of 1 px, which keeps an edge where it is.
    cv::Mat grey;
    cv::cvtColor(out.side_image, grey, cv::COLOR_BGR2GRAY);
    grey.convertTo(grey, CV_32F);
    cv::GaussianBlur(grey, grey, {0, 0}, 1.0, 0.0);
    cv::blur(grey, grey, {1, 5});
    // The silhouette's generators: where the rays from the camera touch the
    // cylinder of the declared radius (their search windows allow 25 % either way).
    const double phi0 = std::atan2(oxy.y(), oxy.x()), beta = std::acos(rec.R2 / dist);
    // The pedestal's own colour: its face nearest the camera near the floor, where
    // no cloth hangs. An edge whose inner side is of another colour is the cloth's.
    const cv::Mat lab = to_lab(out.side_image);
    const Eigen::Vector2d front = oxy / dist * rec.R2;
    const cv::Vec3f ped = sample(lab, cam.project({front.x(), front.y(), -0.9 * rec.pedestal_height}));
    const double px_per_m = cam.fx / (dist - rec.R2);
    const int half_window = std::max(6, static_cast<int>(std::lround(0.25 * rec.R2 * px_per_m)));
    std::vector<double> diam;
    // About one level per image row the pedestal's height spans.
    const double rows_spanned = std::abs(cam.project({front.x(), front.y(), 0.0}).y() -
                                         cam.project({front.x(), front.y(), -rec.pedestal_height}).y());
    const int levels = std::clamp(static_cast<int>(std::isfinite(rows_spanned) ? rows_spanned : 0.0), 20, 600);
    for (int k = 0; k < levels; ++k) {
        // 5-95 % of the pedestal's height below its top: the cloth hangs over the
        // upper part on most records, so a row's edges are kept only if they agree
        // with the others (below).
        const double z = -rec.pedestal_height * (0.05 + 0.90 * (k + 0.5) / levels);
        double r_side[2] = {kNaN, kNaN};
        const double u_axis = cam.project({0.0, 0.0, z}).x(); // inside the edges lies the axis's column
        for (int side = 0; side < 2; ++side) {
            const double phi = phi0 + (side == 0 ? beta : -beta);
            const Eigen::Vector2d p = cam.project({rec.R2 * std::cos(phi), rec.R2 * std::sin(phi), z});
            if (!p.allFinite()) continue;
            const int v = static_cast<int>(std::lround(p.y()));
            const int uc = static_cast<int>(std::lround(p.x()));
            // The window and the parabola's neighbours (best +- 2) inside the image.
            if (v < 0 || v >= grey.rows || uc - half_window < 2 || uc + half_window >= grey.cols - 2) continue;
            const float* row = grey.ptr<float>(v);
            std::vector<double> g;
            int best = -1;
            double best_g = 0;
            for (int u = uc - half_window; u <= uc + half_window; ++u) {
                const double gu = std::abs(0.5 * (row[u + 1] - row[u - 1]));
                g.push_back(gu);
                if (gu > best_g) {
                    best_g = gu;
                    best = u;
                }
            }
            // A step that stands out: 8 grey levels per px and 4 times the window's median.
            if (best < 0 || best_g < 8.0 || best_g < 4.0 * median(g)) continue;
            const double gm = std::abs(0.5 * (row[best] - row[best - 2])), gp = std::abs(0.5 * (row[best + 2] - row[best]));
            const double den = gm - 2 * best_g + gp;
            const double du = den < 0 ? std::clamp(0.5 * (gm - gp) / den, -0.5, 0.5) : 0.0;
            // Inside the edge (towards the axis's column): the pedestal's chroma.
            const double inward = u_axis > best ? 1.0 : -1.0;
            const cv::Vec3f in = sample(lab, {best + inward * 4.0, static_cast<double>(v)});
            if (std::hypot(in[1] - ped[1], in[2] - ped[2]) > 10.0) continue;
            const Eigen::Vector3d d = cam.ray({best + du, static_cast<double>(v)});
            const Eigen::Vector2d dxy(d.x(), d.y());
            if (!(dxy.norm() > 1e-9)) continue;
            // The ray's distance from the axis in the horizontal plane: the radius
            // its tangent touches, whatever the camera's tilt.
            r_side[side] = std::abs(oxy.x() * dxy.y() - oxy.y() * dxy.x()) / dxy.norm();
        }
        if (std::isfinite(r_side[0]) && std::isfinite(r_side[1])) diam.push_back(r_side[0] + r_side[1]);
    }
    if (diam.size() < 10) {
        out.not_measured.push_back("side view: the pedestal's silhouette edges were not found in " + cam.image);
        return;
    }
    // Rows where cloth, a shadow or the floor's print hides an edge disagree with
    // the rest: kept within 3 robust standard deviations (at least 0.6 mm) of the median.
    const double med = median(diam);
    std::vector<double> dev;
    for (double x : diam) dev.push_back(std::abs(x - med));
    const double keep_within = std::max(3 * 1.4826 * median(dev), 6e-4);
    double sum = 0, sum2 = 0;
    int n = 0;
    for (double x : diam)
        if (std::abs(x - med) <= keep_within) {
            sum += x;
            sum2 += x * x;
            ++n;
        }
    if (n < 10) {
        out.not_measured.push_back("side view: the pedestal's silhouette edges disagree from row to row in " + cam.image);
        return;
    }
    const double mean = sum / n, var = std::max(sum2 / n - mean * mean, 0.0);
    pw.measured = true;
    pw.rows = n;
    pw.diameter = mean;
    // The rows' spread, and a quarter pixel of edge placement on each side
    // (blur and anti-aliasing need not be symmetric), which no number of rows averages away.
    pw.diameter_sigma = std::hypot(std::sqrt(var / n), std::sqrt(2.0) * 0.25 / px_per_m);
    pw.differs = std::abs(pw.diameter - pw.declared) > std::max(3 * pw.diameter_sigma, 1.5e-3);
    out.measured.push_back("side view: the pedestal's diameter from its silhouette");
    if (pw.differs)
        out.side.warnings.push_back("side view: the pedestal measures " + fmt("%.1f", pw.diameter * 1e3) + " +- " +
                                    fmt("%.1f", pw.diameter_sigma * 1e3) + " mm across where meta.json declares support_disc_diameter_D2_mm " +
                                    fmt("%.1f", pw.declared * 1e3) + " (a pedestal other than declared, or a side camera's pose off)");
}

} // namespace drape::capture
