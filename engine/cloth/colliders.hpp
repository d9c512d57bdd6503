#pragma once
// Collision objects. Each reports the signed distance from a point to its
// surface (positive outside) and the outward unit normal at the closest point.
// The engine handles contact as a one-sided penalty on that distance, checked
// at every force evaluation (as the seed paper does at every derivative
// evaluation).
#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace drape::cloth {

struct ContactSample {
    double distance = 0.0;            ///< signed distance [m], positive outside
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ(); ///< outward unit normal at the closest point
    /// When query() returns false: how far [m] the point may move and still be
    /// out of the band (the distance is 1-Lipschitz, so a point that moves less
    /// than its distance beyond the band cannot reach it, nor cross the surface).
    /// 0 = not known. The engine skips the query of a vertex that has moved less
    /// than this since (an expensive collider, e.g. a body mesh, sets it).
    double clearance = 0.0;
};

class Collider {
public:
    Collider();
    virtual ~Collider() = default;
    Collider(const Collider&) = delete;
    Collider& operator=(const Collider&) = delete;
    /// Unique for the process's lifetime (never reused, unlike an address): what
    /// remembers answers of this collider keys them on it. A collider does not
    /// change after construction.
    std::uint64_t id() const { return m_id; }
    /// Signed distance and normal at p [m]. May return false when p is farther
    /// than `band` [m] outside the surface (the answer is then not needed); a point
    /// inside must always be answered, however deep, or a vertex pushed through
    /// would feel no force.
    virtual bool query(const Eigen::Vector3d& p, double band, ContactSample& out) const = 0;
    /// Second derivative of the signed distance at p [1/m] (the change of the
    /// normal); zero for planes. Used for an exact contact Hessian near rest.
    virtual Eigen::Matrix3d distance_hessian(const Eigen::Vector3d& /*p*/) const { return Eigen::Matrix3d::Zero(); }
    virtual std::string kind() const = 0;

private:
    std::uint64_t m_id;
};

/// Infinite plane through `point` with outward `normal` (e.g. the floor).
class PlaneCollider final : public Collider {
public:
    PlaneCollider(const Eigen::Vector3d& point, const Eigen::Vector3d& normal);
    bool query(const Eigen::Vector3d& p, double band, ContactSample& out) const override;
    std::string kind() const override { return "plane"; }
    Eigen::Vector3d point, normal;
};

class SphereCollider final : public Collider {
public:
    SphereCollider(const Eigen::Vector3d& centre, double radius);
    bool query(const Eigen::Vector3d& p, double band, ContactSample& out) const override;
    Eigen::Matrix3d distance_hessian(const Eigen::Vector3d& p) const override;
    std::string kind() const override { return "sphere"; }
    Eigen::Vector3d centre;
    double radius;
};

/// The drapemeter pedestal: a vertical solid cylinder of `radius` whose flat top
/// is centred at `top_centre`, reaching `height` down. `edge_radius` rounds the
/// top edge (0 = sharp). Lengths in metres.
class PedestalCollider final : public Collider {
public:
    PedestalCollider(const Eigen::Vector3d& top_centre, double radius, double height, double edge_radius = 0.0);
    bool query(const Eigen::Vector3d& p, double band, ContactSample& out) const override;
    Eigen::Matrix3d distance_hessian(const Eigen::Vector3d& p) const override;
    std::string kind() const override { return "pedestal"; }
    Eigen::Vector3d top_centre;
    double radius, height, edge_radius;
};

/// A union of colliders (the seed's "array of spheres and planes"): the query
/// returns the nearest member.
class ColliderGroup final : public Collider {
public:
    void add(std::shared_ptr<const Collider> c) { members.push_back(std::move(c)); }
    bool query(const Eigen::Vector3d& p, double band, ContactSample& out) const override;
    Eigen::Matrix3d distance_hessian(const Eigen::Vector3d& p) const override;
    std::string kind() const override { return "group"; }
    std::vector<std::shared_ptr<const Collider>> members;
};

} // namespace drape::cloth
