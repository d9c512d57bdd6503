#include "engine/cloth/colliders.hpp"

#include "engine/core/error.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

namespace drape::cloth {

Collider::Collider()
{
    static std::atomic<std::uint64_t> next{1};
    m_id = next.fetch_add(1, std::memory_order_relaxed);
}

PlaneCollider::PlaneCollider(const Eigen::Vector3d& p, const Eigen::Vector3d& n) : point(p), normal(n)
{
    if (!p.allFinite() || !n.allFinite() || n.norm() < 1e-12)
        throw ParameterError("PlaneCollider: point and a non-zero finite normal are required");
    normal.normalize();
}

bool PlaneCollider::query(const Eigen::Vector3d& p, double band, ContactSample& out) const
{
    out.distance = (p - point).dot(normal);
    out.normal = normal;
    return out.distance <= band;
}

SphereCollider::SphereCollider(const Eigen::Vector3d& c, double r) : centre(c), radius(r)
{
    if (!c.allFinite() || !(r > 0)) throw ParameterError("SphereCollider: radius = " + std::to_string(r) + " m must be positive");
}

bool SphereCollider::query(const Eigen::Vector3d& p, double band, ContactSample& out) const
{
    const Eigen::Vector3d d = p - centre;
    const double len = d.norm();
    out.distance = len - radius;
    out.normal = len > 1e-15 ? Eigen::Vector3d(d / len) : Eigen::Vector3d::UnitZ();
    return out.distance <= band;
}

Eigen::Matrix3d SphereCollider::distance_hessian(const Eigen::Vector3d& p) const
{
    const Eigen::Vector3d d = p - centre;
    const double len = d.norm();
    if (len < 1e-15) return Eigen::Matrix3d::Zero();
    const Eigen::Vector3d n = d / len;
    return (Eigen::Matrix3d::Identity() - n * n.transpose()) / len;
}

PedestalCollider::PedestalCollider(const Eigen::Vector3d& t, double r, double h, double e)
    : top_centre(t), radius(r), height(h), edge_radius(e)
{
    if (!(r > 0) || !(h > 0) || !(e >= 0) || e >= r || e >= h || !t.allFinite())
        throw ParameterError("PedestalCollider: need radius > 0 (" + std::to_string(r) + " m), height > 0 (" +
                             std::to_string(h) + " m) and 0 <= edge radius < both (" + std::to_string(e) + " m)");
}

bool PedestalCollider::query(const Eigen::Vector3d& p, double band, ContactSample& out) const
{
    // Work in the (r, h) half-plane: r = distance from the axis, h = height above the top.
    const Eigen::Vector3d q = p - top_centre;
    const double r = std::hypot(q.x(), q.y());
    const double h = q.z();
    const Eigen::Vector2d radial = r > 1e-15 ? Eigen::Vector2d(q.x() / r, q.y() / r) : Eigen::Vector2d(1, 0);
    double d = 0, nr = 0, nh = 0;
    const double rho = edge_radius;
    if (rho > 0 && r > radius - rho && h > -rho) {
        // Rounded top edge: distance to a torus section around the corner centre.
        const double cr = r - (radius - rho), ch = h + rho;
        const double len = std::hypot(cr, ch);
        d = len - rho;
        nr = len > 1e-15 ? cr / len : 1.0;
        nh = len > 1e-15 ? ch / len : 0.0;
    } else {
        const double dr = r - radius, dt = h, db = -height - h;
        if (dr > 0 || dt > 0 || db > 0) {
            const double er = std::max(dr, 0.0);
            // Signed vertical excess: + above the top, - below the bottom.
            const double ehv = dt > 0 ? dt : (db > 0 ? -db : 0.0);
            d = std::hypot(er, ehv);
            nr = er / d;
            nh = ehv / d;
        } else {
            // Inside: the nearest face.
            if (dr >= dt && dr >= db) {
                d = dr;
                nr = 1;
            } else if (dt >= db) {
                d = dt;
                nh = 1;
            } else {
                d = db;
                nh = -1;
            }
        }
    }
    out.distance = d;
    out.normal = Eigen::Vector3d(nr * radial.x(), nr * radial.y(), nh);
    return d <= band;
}

Eigen::Matrix3d PedestalCollider::distance_hessian(const Eigen::Vector3d& p) const
{
    // The distance depends on (r, h) only. In the (radial, vertical) plane it is
    // the distance to a point (the rounded edge's centre line, or the sharp edge)
    // or to a line (faces); around the axis it bends with the circle of radius r.
    const Eigen::Vector3d q = p - top_centre;
    const double r = std::hypot(q.x(), q.y());
    if (r < 1e-12) return Eigen::Matrix3d::Zero();
    const Eigen::Vector3d er(q.x() / r, q.y() / r, 0), t(-q.y() / r, q.x() / r, 0), ez(0, 0, 1);
    ContactSample cs;
    query(p, 1e300, cs);
    const double nr = cs.normal.dot(er);
    Eigen::Matrix3d H = (nr / r) * t * t.transpose(); // azimuthal curvature of the level set
    const double h = q.z(), rho = edge_radius;
    double L = -1; // distance to the point feature in the (r, h) plane, when the nearest feature is a point
    if (rho > 0 && r > radius - rho && h > -rho) L = std::hypot(r - (radius - rho), h + rho);
    else if (r > radius && (h > 0 || h < -height)) L = cs.distance;
    if (L > 1e-12) {
        const Eigen::Vector3d n2 = nr * er + cs.normal.dot(ez) * ez;
        const Eigen::Vector3d perp = (ez * n2.dot(er) - er * n2.dot(ez)).normalized();
        H += perp * perp.transpose() / L;
    }
    return H;
}

Eigen::Matrix3d ColliderGroup::distance_hessian(const Eigen::Vector3d& p) const
{
    ContactSample best, s;
    const Collider* nearest = nullptr;
    best.distance = std::numeric_limits<double>::infinity();
    for (const auto& c : members)
        if (c->query(p, 1e300, s) && s.distance < best.distance) {
            best = s;
            nearest = c.get();
        }
    return nearest ? nearest->distance_hessian(p) : Eigen::Matrix3d::Zero();
}

bool ColliderGroup::query(const Eigen::Vector3d& p, double band, ContactSample& out) const
{
    bool any = false;
    out.distance = std::numeric_limits<double>::infinity();
    double clearance = std::numeric_limits<double>::infinity();
    for (const auto& c : members) {
        ContactSample s;
        if (c->query(p, band, s)) {
            if (s.distance < out.distance) out = s;
            any = true;
        } else {
            clearance = std::min(clearance, s.clearance);
        }
    }
    out.clearance = any || !std::isfinite(clearance) ? 0.0 : clearance;
    return any;
}

} // namespace drape::cloth
