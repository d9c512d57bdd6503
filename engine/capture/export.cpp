#include "engine/capture/export.hpp"

#include "engine/core/error.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>

namespace drape::capture {

cv::Mat rectified_texture(const record::Record& rec, const Measurement& m, double metres_per_pixel)
{
    if (m.top_image.empty() || !m.top.measured)
        throw ParameterError("rectified_texture: the record has no measured top view");
    if (!(metres_per_pixel > 0)) throw ParameterError("rectified_texture: metres_per_pixel must be > 0");
    const record::Camera cam = m.view ? m.view->camera : rec.cameras.at("top");
    const double half = rec.specimen.max_reach();
    const int n = static_cast<int>(std::ceil(2 * half / metres_per_pixel));
    // Hem radius and height per ray, from the traced outline.
    const int rays = static_cast<int>(m.top.outline.size());
    std::vector<double> r_hem(static_cast<std::size_t>(rays), 0.0), z_hem(static_cast<std::size_t>(rays), 0.0);
    for (int k = 0; k < rays; ++k) {
        const auto& p = m.top.outline[static_cast<std::size_t>(k)];
        double th = std::atan2(p.y(), p.x());
        if (th < 0) th += 2 * M_PI;
        const int slot = static_cast<int>(std::lround(th / (2 * M_PI) * rays)) % rays;
        r_hem[static_cast<std::size_t>(slot)] = p.norm();
        z_hem[static_cast<std::size_t>(slot)] = m.top.outline_z[static_cast<std::size_t>(k)];
    }
    cv::Mat mapx(n, n, CV_32F, cv::Scalar(-1e4)), mapy(n, n, CV_32F, cv::Scalar(-1e4));
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const double x = -half + (j + 0.5) * metres_per_pixel, y = half - (i + 0.5) * metres_per_pixel;
            const double r = std::hypot(x, y);
            double th = std::atan2(y, x);
            if (th < 0) th += 2 * M_PI;
            const auto slot = static_cast<std::size_t>(std::lround(th / (2 * M_PI) * rays) % rays);
            if (r > r_hem[slot]) continue; // outside the shadow outline: left white
            // The hanging part is taken as a cone from the disc edge (z = 0) to
            // the hem height found for this ray, so each texel shows the cloth
            // straight above/below its vertical projection.
            const double z = r <= rec.R2 ? 0.0 : z_hem[slot] * (r - rec.R2) / std::max(r_hem[slot] - rec.R2, 1e-6);
            const Eigen::Vector2d u = cam.project({x, y, z});
            mapx.at<float>(i, j) = static_cast<float>(u.x());
            mapy.at<float>(i, j) = static_cast<float>(u.y());
        }
    cv::Mat out;
    cv::remap(m.top_image, out, mapx, mapy, cv::INTER_CUBIC, cv::BORDER_CONSTANT, cv::Scalar(255, 255, 255));
    return out;
}

SurfaceMesh contour_surface(const record::Record& rec, const Measurement& m, int segments)
{
    if (m.contours.empty()) throw ParameterError("contour_surface: the record has no fitted contour levels");
    if (segments < 8) throw ParameterError("contour_surface: segments must be >= 8");
    std::vector<const ContourLevel*> levels;
    for (const auto& c : m.contours) levels.push_back(&c);
    std::sort(levels.begin(), levels.end(), [](auto a, auto b) { return a->depth < b->depth; });
    SurfaceMesh mesh;
    auto ring = [&](auto radius, double z) {
        for (int k = 0; k < segments; ++k) {
            const double th = 2 * M_PI * k / segments, r = radius(th);
            mesh.vertices.emplace_back(r * std::cos(th), r * std::sin(th), z);
        }
    };
    ring([&](double) { return rec.R2; }, 0.0); // the fabric leaves the disc at its edge
    for (const auto* c : levels) ring([&](double th) { return c->fit.evaluate(th); }, -c->depth);
    const int rings = static_cast<int>(levels.size()) + 1;
    for (int r = 0; r + 1 < rings; ++r)
        for (int k = 0; k < segments; ++k) {
            const int a = r * segments + k, b = r * segments + (k + 1) % segments;
            const int c = a + segments, d = b + segments;
            mesh.triangles.push_back({a, c, b});
            mesh.triangles.push_back({b, c, d});
        }
    return mesh;
}

void write_obj(const SurfaceMesh& mesh, const std::filesystem::path& file)
{
    std::ofstream out(file);
    if (!out) throw FileError(file.string() + ": cannot be written");
    out << "# drape contour surface, metres, world frame (origin = pedestal-top centre, z up)\n";
    out.precision(9);
    for (const auto& v : mesh.vertices) out << "v " << v.x() << ' ' << v.y() << ' ' << v.z() << '\n';
    for (const auto& t : mesh.triangles) out << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
    if (!out) throw FileError(file.string() + ": write failed");
}

} // namespace drape::capture
