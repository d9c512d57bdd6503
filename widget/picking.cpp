#include "widget/picking.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <limits>

namespace drape::widget {

int pickVertex(const OrbitCamera& camera, const cloth::Positions& X, const cloth::Triangles& F, double x, double y,
               double w, double h)
{
    if (w <= 0 || h <= 0 || X.rows() == 0) return -1;
    Eigen::Vector3d o, d;
    camera.ray(x, y, w, h, o, d);
    double best = std::numeric_limits<double>::infinity();
    Eigen::Index bestT = -1;
    // Moller-Trumbore against every triangle: a 10,000-vertex cloth takes well
    // under a millisecond.
    for (Eigen::Index t = 0; t < F.rows(); ++t) {
        const Eigen::Vector3d a = X.row(F(t, 0)), b = X.row(F(t, 1)), c = X.row(F(t, 2));
        const Eigen::Vector3d e1 = b - a, e2 = c - a, p = d.cross(e2);
        const double det = e1.dot(p);
        if (std::abs(det) < 1e-18) continue;
        const double inv = 1.0 / det;
        const Eigen::Vector3d s = o - a;
        const double u = s.dot(p) * inv;
        if (u < 0 || u > 1) continue;
        const Eigen::Vector3d q = s.cross(e1);
        const double v = d.dot(q) * inv;
        if (v < 0 || u + v > 1) continue;
        const double dist = e2.dot(q) * inv;
        if (dist > 0 && dist < best) {
            best = dist;
            bestT = t;
        }
    }
    if (bestT < 0) return -1;
    const Eigen::Vector3d hit = o + best * d;
    int vertex = -1;
    double nearest = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 3; ++k) {
        const int i = F(bestT, k);
        const double r = (X.row(i).transpose() - hit).squaredNorm();
        if (r < nearest) {
            nearest = r;
            vertex = i;
        }
    }
    return vertex;
}

} // namespace drape::widget
