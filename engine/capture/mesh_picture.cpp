#include "engine/capture/mesh_picture.hpp"

#include "engine/core/error.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace drape::capture {

namespace {

struct Face {
    double depth;         ///< larger = farther from the viewer
    cv::Point pts[3];
    cv::Scalar colour;
};

/// One orthographic view: `right` and `up` span the image plane, `toward` points at the viewer.
void draw_view(cv::Mat& img, const cv::Rect& area, const std::vector<PictureMesh>& meshes, const Eigen::Vector3d& right,
               const Eigen::Vector3d& up, const Eigen::Vector3d& toward, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
               const std::string& label)
{
    const Eigen::Vector3d centre = 0.5 * (lo + hi);
    const Eigen::Vector3d ext = hi - lo;
    const double w = std::abs(ext.dot(right)), h = std::abs(ext.dot(up));
    const double scale = 0.88 * std::min(area.width / std::max(w, 1e-6), area.height / std::max(h, 1e-6)); // px per m
    auto to_px = [&](const Eigen::Vector3d& x) {
        const Eigen::Vector3d d = x - centre;
        return cv::Point(static_cast<int>(std::lround(area.x + 0.5 * area.width + scale * d.dot(right))),
                         static_cast<int>(std::lround(area.y + 0.5 * area.height - scale * d.dot(up))));
    };
    const Eigen::Vector3d light = (toward + 0.5 * up - 0.4 * right).normalized();
    std::vector<Face> faces;
    for (const auto& m : meshes) {
        if (!m.X || !m.F) continue;
        const auto& X = *m.X;
        const auto& F = *m.F;
        for (Eigen::Index t = 0; t < F.rows(); ++t) {
            const Eigen::Vector3d a = X.row(F(t, 0)), b = X.row(F(t, 1)), c = X.row(F(t, 2));
            Eigen::Vector3d n = (b - a).cross(c - a);
            if (n.squaredNorm() < 1e-30) continue;
            n.normalize();
            // Both sides of cloth are visible: shade by |n . l|.
            const double lambert = 0.25 + 0.75 * std::abs(n.dot(light));
            Face f;
            f.depth = -((a + b + c) / 3.0).dot(toward);
            f.pts[0] = to_px(a);
            f.pts[1] = to_px(b);
            f.pts[2] = to_px(c);
            f.colour = m.colour * lambert;
            faces.push_back(f);
        }
    }
    std::sort(faces.begin(), faces.end(), [](const Face& x, const Face& y) { return x.depth > y.depth; });
    for (const auto& f : faces) cv::fillConvexPoly(img, f.pts, 3, f.colour, cv::LINE_AA);
    cv::putText(img, label, {area.x + 10, area.y + 22}, cv::FONT_HERSHEY_SIMPLEX, 0.6, {40, 40, 40}, 1, cv::LINE_AA);
    // 10 cm scale bar.
    const int bar = static_cast<int>(std::lround(0.1 * scale));
    const cv::Point p0(area.x + 12, area.y + area.height - 16), p1(p0.x + bar, p0.y);
    cv::line(img, p0, p1, {30, 30, 30}, 2);
    cv::putText(img, "10 cm", {p0.x, p0.y - 6}, cv::FONT_HERSHEY_SIMPLEX, 0.45, {30, 30, 30}, 1, cv::LINE_AA);
}

} // namespace

cv::Mat mesh_picture(const std::vector<PictureMesh>& meshes, const std::string& title, int panel)
{
    panel = std::clamp(panel, 100, 4000);
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
    for (const auto& m : meshes)
        if (m.X && m.X->rows() > 0) {
            if (!m.X->allFinite()) throw ParameterError("mesh picture: a vertex position is not finite");
            lo = lo.cwiseMin(m.X->colwise().minCoeff().transpose());
            hi = hi.cwiseMax(m.X->colwise().maxCoeff().transpose());
        }
    if (!(lo.array() <= hi.array()).all()) throw ParameterError("mesh picture: nothing to draw");
    const int top_bar = 34;
    cv::Mat img(panel + top_bar, 2 * panel, CV_8UC3, cv::Scalar(245, 245, 245));
    cv::putText(img, title, {10, 23}, cv::FONT_HERSHEY_SIMPLEX, 0.6, {20, 20, 20}, 1, cv::LINE_AA);
    draw_view(img, {0, top_bar, panel, panel}, meshes, Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitZ(), -Eigen::Vector3d::UnitY(),
              lo, hi, "front (from -y)");
    draw_view(img, {panel, top_bar, panel, panel}, meshes, Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(),
              Eigen::Vector3d::UnitZ(), lo, hi, "top (from +z)");
    cv::line(img, {panel, top_bar}, {panel, panel + top_bar}, {200, 200, 200}, 1);
    return img;
}

void write_mesh_picture(const std::string& path, const std::vector<PictureMesh>& meshes, const std::string& title, int panel)
{
    const cv::Mat img = mesh_picture(meshes, title, panel);
    bool ok = false;
    try {
        ok = cv::imwrite(path, img);
    } catch (const cv::Exception& e) {
        throw FileError(path + ": cannot write the picture (" + e.what() + ")");
    }
    if (!ok) throw FileError(path + ": cannot write the picture");
}

} // namespace drape::capture
