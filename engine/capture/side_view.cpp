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

} // namespace drape::capture
