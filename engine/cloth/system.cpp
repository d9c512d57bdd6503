#include "engine/cloth/system.hpp"

#include "engine/core/error.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace drape::cloth {

using Vec3 = Eigen::Vector3d;

namespace {

/// An arc spring at positions X (SpringArc): its arc and chord, and the gradient
/// of the arc in each of its nodes (SpringArc::v).
struct ArcTerm {
    Vec3 g[SpringArc::kMax]; // dL / dx_v
    double L = 0, l = 0;     // arc, chord
    Vec3 u;                  // the chord's direction (v[0] - v[1])
    Vec3 s[2];
};

/// false: zero chord.
template <class P>
bool arc_term(const SpringArc& arc, const P& X, ArcTerm& t)
{
    t.L = arc.length(X, t.s);
    const Vec3 d = X.row(arc.v[0]) - X.row(arc.v[1]);
    t.l = d.norm();
    if (t.l <= 1e-300) return false;
    t.u = d / t.l;
    for (int p = 0; p < arc.n; ++p) t.g[p] = 2 * (arc.c[0] * arc.w[0][p] * t.s[0] + arc.c[1] * arc.w[1][p] * t.s[1]);
    t.g[0] += t.u;
    t.g[1] -= t.u;
    return true;
}

} // namespace

ClothSystem::ClothSystem(ClothMesh mesh, ClothModel model) : m_mesh(std::move(mesh)), m_model(std::move(model))
{
    const int n = m_mesh.vertex_count();
    if (m_model.vertex_count() != n)
        throw ParameterError("ClothSystem: model has " + std::to_string(m_model.vertex_count()) + " vertices, mesh " + std::to_string(n));
    x = m_mesh.X;
    v = Positions::Zero(n, 3);
    for (int f = 0; f < m_mesh.F.rows(); ++f)
        for (int c = 0; c < m_mesh.F.cols(); ++c) {
            const int a = m_mesh.F(f, c), b = m_mesh.F(f, (c + 1) % m_mesh.F.cols());
            m_edges.push_back({std::min(a, b), std::max(a, b)});
        }
    std::sort(m_edges.begin(), m_edges.end());
    m_edges.erase(std::unique(m_edges.begin(), m_edges.end()), m_edges.end());
    m_self = SelfContact(m_mesh.F, m_edges, m_mesh.X);
}

const std::vector<ProximityPair>& ClothSystem::self_contact_pairs(const Positions& X) const
{
    static const std::vector<ProximityPair> none;
    if (!self_contact_on()) return none;
    ProfileScope timer(profile ? &profile->self_contact : nullptr);
    return m_self.pairs(X, m_model.self_contact_distance, m_model.pinned);
}

double ClothSystem::self_contact_pair_energy(const ProximityPair& p, const Positions& X, Vec12* grad, Mat12* hess) const
{
    // Stiffness: a quarter of the pair's vertices' weight over a quarter of the
    // contact distance, so one layer's weight rests on another about 0.8 d_hat
    // apart (the fabric's thickness squeezed a little), not the collider
    // penalty's micrometres: a barrier that stiff turned a Newton step that
    // brings two folds into range into a line search of tiny steps.
    const double g = std::max(m_model.gravity.norm(), 1.0), d_hat = m_model.self_contact_distance;
    double k = 0;
    for (int vi : p.v) k += 0.25 * m_model.mass(vi) * g / (kSelfContactSqueeze * d_hat);
    const std::array<Vec3, 4> xp = {X.row(p.v[0]).transpose(), X.row(p.v[1]).transpose(), X.row(p.v[2]).transpose(),
                                    X.row(p.v[3]).transpose()};
    return pair_energy(p.kind, xp, k, m_model.self_contact_distance, m_self.eps_cross(p), grad, hess);
}

double ClothSystem::self_contact_step_bound(const Positions& X, const Positions& D) const
{
    if (!self_contact_on()) return 1.0;
    ProfileScope timer(profile ? &profile->self_contact : nullptr);
    return m_self.step_bound(X, D, m_model.self_contact_distance, m_model.pinned);
}

void ClothSystem::set_pinned(int vertex, bool p)
{
    if (vertex < 0 || vertex >= vertex_count())
        throw ParameterError("set_pinned: vertex " + std::to_string(vertex) + " is outside [0, " + std::to_string(vertex_count() - 1) + "]");
    m_model.pinned[static_cast<std::size_t>(vertex)] = p ? 1 : 0;
    if (p) v.row(vertex).setZero();
}

void ClothSystem::set_mass(int vertex, double mass)
{
    if (vertex < 0 || vertex >= vertex_count())
        throw ParameterError("set_mass: vertex " + std::to_string(vertex) + " is outside [0, " + std::to_string(vertex_count() - 1) + "]");
    if (!(mass > 0) || !std::isfinite(mass)) throw ParameterError("set_mass: mass " + std::to_string(mass) + " kg must be positive");
    const double ratio = mass / m_model.mass(vertex);
    m_model.mass(vertex) = mass;
    m_model.contact_stiffness(vertex) *= ratio;
}

namespace {

/// The bending law of one stencil at s2 = |d|^2, d = sum w_a x_a: energy k g(sig) with
/// g = (sqrt(1 + rho2 sig) - 1) / rho2 + beta sig^2 / 4 (g = sig / 2 + beta sig^2 / 4
/// without softening; g = ln(1 + peak2 sig) / (2 peak2) + beta sig^2 / 4 with the
/// peaking law) of the corrected squared curvature sig = s2 (1 + quartic s2 / 2)
/// (ClothModel::bend_stiffening = beta, bend_softening = rho2, bend_peak = peak2, BendStencil::quartic;
/// sig = s2 without the correction). The force is -k g1 ds d; the Hessian in d is
/// k (c I + 2 c' d d^T) with c = g1 ds and c' = g2 ds^2 + g1 quartic. Without the
/// correction that is k ((1/q + beta s2) I + (2 beta - rho2/q^3) d d^T), positive
/// definite (1/q^3 + 3 beta s2 along d). The energy, the forces and the Hessian
/// assembler all evaluate the law here.
struct BendLaw {
    double g;  ///< g(sig): the energy over k
    double g1; ///< 2 g'(sig) = 1/q + beta sig, q = sqrt(1 + rho2 sig)
    double g2; ///< 2 g''(sig) = beta - rho2 / (2 q^3)
    double ds; ///< d sig / d s2 = 1 + quartic s2
};

BendLaw bend_law(double s2, double quartic, double beta, double rho2, double peak2)
{
    const double sig = s2 * (1.0 + 0.5 * quartic * s2);
    BendLaw l;
    l.ds = 1.0 + quartic * s2;
    if (peak2 > 0) {
        // The peaking law (ClothModel::bend_peak = R^2): g = ln(1 + R^2 sig) / (2 R^2).
        const double u = 1.0 + peak2 * sig;
        l.g = std::log1p(peak2 * sig) / (2 * peak2) + 0.25 * beta * sig * sig;
        l.g1 = 1.0 / u + beta * sig;
        l.g2 = beta - peak2 / (u * u);
        return l;
    }
    const double q = rho2 > 0 ? std::sqrt(1.0 + rho2 * sig) : 1.0;
    l.g = (rho2 > 0 ? (q - 1.0) / rho2 : 0.5 * sig) + 0.25 * beta * sig * sig;
    l.g1 = 1.0 / q + beta * sig;
    l.g2 = beta - rho2 / (2 * q * q * q);
    return l;
}

} // namespace

/// One edge in contact at an interior point: p(t) = (1 - t) x_a + t x_b is the
/// point of the edge deepest in the offset surface (phi(p(t)) minimal in t).
struct EdgeContact {
    int edge;         ///< index into ClothSystem::edges()
    double t;         ///< (0, 1)
    double phi;       ///< < 0 [m]
    Vec3 n;           ///< outward normal at p(t)
    Eigen::Matrix3d H;///< distance Hessian at p(t) [1/m]
    Vec3 e;           ///< x_b - x_a [m]
    double k;         ///< penalty stiffness [N/m]
    Eigen::Matrix<double, 6, 1> g; ///< d/d(x_a, x_b) of phi'(t) = n . e
    /// Fade w = S(da / eps) S(db / eps) on the excess depths da, db >= 0 of the
    /// deepest point below the end points' distances, and what its derivatives need.
    double sa, sb;    ///< the factors S(da / eps), S(db / eps)
    double sa1, sa2, sb1, sb2; ///< S', S'' of each factor (per metre, per metre^2)
    Vec3 na, nb;      ///< normals at the end points
    const Collider* collider; ///< for the end points' distance Hessians (exact Hessian only)
    Vec3 xa, xb;      ///< the end points [m]
    double w() const { return sa * sb; }
};

namespace {

/// The edge contact fades out as the edge's deepest point comes up to the depth
/// of one of its end points (which the vertex contact then covers): the energy
/// is k phi^2 w / 2 with w = S(da / eps) S(db / eps), S the C1 smoothstep, da and
/// db how much deeper the deepest point is than each end. Both are C1 in the
/// positions (Danskin), so the energy is C1 where the minimum leaves through an
/// end point (without the fade it jumps by k phi^2 / 2 there, and a limp drape
/// stalled on the pedestal rim for 1000 Newton iterations; a fade in t instead
/// is only C0, because t jumps where the collider's curvature does).
constexpr double kEdgeFadeDepth = 1e-4; // [m]
inline double smoothstep(double u, double& ds, double& d2s)
{
    if (u >= 1) { ds = d2s = 0; return 1.0; }
    if (u <= 0) { ds = d2s = 0; return 0.0; }
    ds = 6 * u * (1 - u);
    d2s = 6 - 12 * u;
    return u * u * (3 - 2 * u);
}

/// Gradient / k of the edge contact energy k phi^2 w / 2 in (x_a, x_b), and
/// (optionally) its Hessian / k. `exact` false: the Gauss-Newton part only
/// (positive semidefinite), for the projected Hessian.
inline void edge_gradients(const EdgeContact& c, Eigen::Matrix<double, 6, 1>& grad, Eigen::Matrix<double, 6, 6>* hess = nullptr,
                           bool exact = true)
{
    using V6 = Eigen::Matrix<double, 6, 1>;
    using M6 = Eigen::Matrix<double, 6, 6>;
    V6 G, Ga, Gb;
    G << (1 - c.t) * c.n, c.t * c.n;
    Ga << c.na, Vec3::Zero();
    Ga -= G;
    Gb << Vec3::Zero(), c.nb;
    Gb -= G;
    const double wa = c.sa1 * c.sb, wb = c.sa * c.sb1; // dw/dda, dw/ddb
    const V6 Gw = wa * Ga + wb * Gb;
    const double w = c.w();
    grad = c.phi * w * G + 0.5 * c.phi * c.phi * Gw;
    if (!hess) return;
    M6& K = *hess;
    K = w * G * G.transpose();
    if (!exact) return;
    // Hessian of phi (Danskin, t interior): [w_p w_q H] - g g^T / (e^T H e).
    // No curvature along the edge at an interior minimum: the minimum sits on a
    // seam of the collider's distance (deep inside, where the nearest face
    // changes); the Danskin correction is then left out.
    const double wt[2] = {1 - c.t, c.t};
    M6 Hphi;
    for (int p = 0; p < 2; ++p)
        for (int q = 0; q < 2; ++q) Hphi.block<3, 3>(3 * p, 3 * q) = wt[p] * wt[q] * c.H;
    const double gtt = c.e.dot(c.H * c.e);
    if (gtt > 1e-9 * c.e.norm()) Hphi -= c.g * c.g.transpose() / gtt;
    M6 Hw = c.sa2 * c.sb * Ga * Ga.transpose() + c.sa1 * c.sb1 * (Ga * Gb.transpose() + Gb * Ga.transpose()) +
            c.sa * c.sb2 * Gb * Gb.transpose();
    if (wa != 0 || wb != 0) { // in the fade zone: Hess(da) = [H_a 0; 0 0] - Hess(phi), Hess(db) likewise
        M6 Hda = -Hphi, Hdb = -Hphi;
        Hda.block<3, 3>(0, 0) += c.collider->distance_hessian(c.xa);
        Hdb.block<3, 3>(3, 3) += c.collider->distance_hessian(c.xb);
        Hw += wa * Hda + wb * Hdb;
    }
    K += c.phi * w * Hphi + c.phi * (G * Gw.transpose() + Gw * G.transpose()) + 0.5 * c.phi * c.phi * Hw;
}

/// The deepest point of the segment x_a -> x_b in collider c, when it lies inside
/// the segment (0 < t < 1) and inside the offset surface. Fills everything of
/// EdgeContact except edge and k. The distance is convex along a segment for
/// curved convex colliders (pedestal, sphere), so its minimum is found by
/// golden section and polished by Newton. Minima at an end point are the
/// vertex contact's; planes (distance linear along an edge) never have
/// interior minima.
bool edge_deepest_point(const Collider& c, const Vec3& xa, const Vec3& xb, double off, EdgeContact& out)
{
    const Vec3 e = xb - xa;
    const double L = e.norm();
    if (L <= 1e-12) return false;
    // Every point of the edge is within L/2 of an end point.
    ContactSample ca, cb;
    const bool qa = c.query(xa, 0.5 * L + off, ca), qb = c.query(xb, 0.5 * L + off, cb);
    if (!qa && !qb) return false;
    // The distance is convex along the edge: its minimum is inside only
    // if it falls leaving x_a and rises arriving at x_b.
    if (!qa) c.query(xa, 1e300, ca);
    if (!qb) c.query(xb, 1e300, cb);
    if (ca.normal.dot(e) >= 0 || cb.normal.dot(e) <= 0) return false;
    auto dist = [&](double t) {
        ContactSample cs;
        c.query(xa + t * e, 1e300, cs);
        return cs.distance;
    };
    double lo = 0, hi = 1;
    const double gr = 0.5 * (std::sqrt(5.0) - 1);
    double t1 = hi - gr * (hi - lo), t2 = lo + gr * (hi - lo), d1 = dist(t1), d2 = dist(t2);
    for (int it = 0; it < 40 && hi - lo > 1e-7; ++it) {
        if (d1 < d2) {
            hi = t2;
            t2 = t1;
            d2 = d1;
            t1 = hi - gr * (hi - lo);
            d1 = dist(t1);
        } else {
            lo = t1;
            t1 = t2;
            d1 = d2;
            t2 = lo + gr * (hi - lo);
            d2 = dist(t2);
        }
    }
    double t = 0.5 * (lo + hi);
    ContactSample cs;
    Eigen::Matrix3d H;
    // Newton on d/dt phi = n . e polishes a smooth minimum to full precision.
    // Its steps stay within a few golden-section brackets: at a minimum on a
    // seam of the distance (deep inside, where the nearest face changes) the
    // curvature is ~0 and a Newton step would throw t to an end point.
    const double reach = 4 * (hi - lo) + 1e-12;
    const double t_gs = t;
    for (int it = 0; it < 3; ++it) {
        c.query(xa + t * e, 1e300, cs);
        H = c.distance_hessian(xa + t * e);
        const double gt = cs.normal.dot(e), gtt = e.dot(H * e);
        if (!(gtt > 1e-12 * L)) break;
        const double tn = t - gt / gtt;
        if (!(std::abs(tn - t_gs) <= reach)) break;
        t = tn;
    }
    if (t <= 0 || t >= 1) return false;
    c.query(xa + t * e, 1e300, cs);
    const double phi = cs.distance - off;
    if (phi >= 0) return false;
    // A minimum on a seam of the distance (no curvature along the edge) is kept:
    // it is still the edge's deepest point, and dropping it made the energy jump.
    H = c.distance_hessian(xa + t * e);
    const double da = std::max(ca.distance - cs.distance, 0.0), db = std::max(cb.distance - cs.distance, 0.0);
    const double eps = kEdgeFadeDepth;
    double sa1, sa2, sb1, sb2;
    const double sa = smoothstep(da / eps, sa1, sa2), sb = smoothstep(db / eps, sb1, sb2);
    if (sa <= 0 || sb <= 0) return false;
    const Vec3 He = H * e;
    out.t = t;
    out.phi = phi;
    out.n = cs.normal;
    out.H = H;
    out.e = e;
    out.g << (1 - t) * He - cs.normal, t * He + cs.normal;
    out.sa = sa;
    out.sb = sb;
    out.sa1 = sa1 / eps;
    out.sa2 = sa2 / (eps * eps);
    out.sb1 = sb1 / eps;
    out.sb2 = sb2 / (eps * eps);
    out.na = ca.normal;
    out.nb = cb.normal;
    out.collider = &c;
    out.xa = xa;
    out.xb = xb;
    return true;
}

} // namespace

/// A vertex in contact: phi = distance - offset < 0 [m], outward normal n.
struct VertexContact {
    int i;
    double phi;
    Vec3 n;
    const Collider* collider;
};

/// The contacts at one set of positions, for one set of colliders, offset and
/// pinned vertices: forces, energy and Hessian at the same positions (a Newton
/// iteration asks for all three) query the colliders once. The key is compared
/// in full (positions bit for bit), so a stale answer is impossible.
struct ContactCache {
    Positions x;
    double offset = std::numeric_limits<double>::quiet_NaN();
    std::vector<char> pinned;
    std::vector<const Collider*> colliders;
    bool edge_flag = false;
    bool vertex_valid = false, edge_valid = false;
    std::vector<VertexContact> vertex;
    std::vector<EdgeContact> edge;

    /// Per collider and vertex: where the vertex was last queried and how far it
    /// may move from there and still be out of contact (ContactSample::clearance).
    /// Kept across positions (a line search's trial points, the next iterations);
    /// reset when the colliders, the offset or the vertex count change.
    struct Clearance {
        std::vector<std::uint64_t> ids;
        double offset = std::numeric_limits<double>::quiet_NaN();
        Eigen::Index rows = -1;
        std::vector<Positions> from;
        std::vector<std::vector<double>> radius;
    } clearance;

    void use_clearance(const ClothSystem& s, Eigen::Index rows)
    {
        const auto& cs = s.colliders();
        bool same = clearance.rows == rows && clearance.offset == s.model().contact_offset && clearance.ids.size() == cs.size();
        for (std::size_t k = 0; same && k < cs.size(); ++k) same = clearance.ids[k] == cs[k]->id();
        if (same) return;
        clearance.ids.clear();
        for (const auto& c : cs) clearance.ids.push_back(c->id());
        clearance.offset = s.model().contact_offset;
        clearance.rows = rows;
        clearance.from.assign(cs.size(), Positions::Zero(rows, 3));
        clearance.radius.assign(cs.size(), std::vector<double>(static_cast<std::size_t>(rows), 0.0));
    }

    void use(const ClothSystem& s, const Positions& X)
    {
        const auto& m = s.model();
        const auto& cs = s.colliders();
        bool same = x.rows() == X.rows() && offset == m.contact_offset && edge_flag == m.edge_contact && pinned == m.pinned &&
                    colliders.size() == cs.size();
        for (std::size_t k = 0; same && k < cs.size(); ++k) same = colliders[k] == cs[k].get();
        same = same && std::memcmp(x.data(), X.data(), sizeof(double) * static_cast<std::size_t>(X.size())) == 0;
        if (same) return;
        x = X;
        offset = m.contact_offset;
        edge_flag = m.edge_contact;
        pinned = m.pinned;
        colliders.clear();
        for (const auto& c : cs) colliders.push_back(c.get());
        vertex_valid = edge_valid = false;
    }
};

ContactCacheHolder::ContactCacheHolder() : m_p(std::make_unique<ContactCache>()) {}
ContactCacheHolder::~ContactCacheHolder() = default;
ContactCacheHolder::ContactCacheHolder(const ContactCacheHolder&) : m_p(std::make_unique<ContactCache>()) {}
ContactCacheHolder& ContactCacheHolder::operator=(const ContactCacheHolder&)
{
    m_p = std::make_unique<ContactCache>();
    return *this;
}

namespace {

/// Calls f(i, phi, n, collider) for every free vertex inside a collider's offset
/// surface (phi = distance - offset < 0), collider by collider.
template <class F>
void for_each_contact(const ClothSystem& s, const Positions& X, F&& f)
{
    ContactCache& cc = s.contact_cache();
    cc.use(s, X);
    if (!cc.vertex_valid) {
        ProfileScope timer(s.profile ? &s.profile->vertex_contact : nullptr);
        const auto& m = s.model();
        const double off = m.contact_offset;
        cc.vertex.clear();
        cc.use_clearance(s, X.rows());
        const auto& colliders = s.colliders();
        for (std::size_t k = 0; k < colliders.size(); ++k) {
            const Collider& c = *colliders[k];
            Positions& from = cc.clearance.from[k];
            std::vector<double>& radius = cc.clearance.radius[k];
            for (int i = 0; i < X.rows(); ++i) {
                if (m.pinned[static_cast<std::size_t>(i)]) continue;
                double& r = radius[static_cast<std::size_t>(i)];
                if (r > 0 && (X.row(i) - from.row(i)).squaredNorm() < r * r) continue; // still out of reach
                ContactSample cs;
                if (!c.query(X.row(i).transpose(), off, cs)) {
                    r = cs.clearance;
                    if (r > 0) from.row(i) = X.row(i);
                    continue;
                }
                r = 0;
                const double phi = cs.distance - off;
                if (phi < 0) cc.vertex.push_back({i, phi, cs.normal, &c});
            }
        }
        cc.vertex_valid = true;
    }
    for (const auto& c : cc.vertex) f(c.i, c.phi, c.n, *c.collider);
}

/// Calls f(EdgeContact) for every mesh edge whose deepest point in a curved
/// collider is inside the edge and in contact.
template <class F>
void for_each_edge_contact(const ClothSystem& s, const Positions& X, F&& f)
{
    const auto& m = s.model();
    if (!m.edge_contact) return;
    ContactCache& cc = s.contact_cache();
    cc.use(s, X);
    if (!cc.edge_valid) {
        ProfileScope timer(s.profile ? &s.profile->edge_contact : nullptr);
        const double off = m.contact_offset;
        const auto& edges = s.edges();
        cc.edge.clear();
        for (const auto& c : s.colliders()) {
            const std::string kind = c->kind();
            if (kind != "pedestal" && kind != "sphere") continue;
            for (std::size_t ei = 0; ei < edges.size(); ++ei) {
                const int a = edges[ei][0], b = edges[ei][1];
                if (m.pinned[static_cast<std::size_t>(a)] && m.pinned[static_cast<std::size_t>(b)]) continue;
                EdgeContact ec;
                if (!edge_deepest_point(*c, X.row(a).transpose(), X.row(b).transpose(), off, ec)) continue;
                ec.edge = static_cast<int>(ei);
                cc.edge.push_back(ec);
            }
        }
        cc.edge_valid = true;
    }
    for (auto& ec : cc.edge) {
        const auto& e = s.edges()[static_cast<std::size_t>(ec.edge)];
        ec.k = 0.5 * (m.contact_stiffness(e[0]) + m.contact_stiffness(e[1]));
        f(static_cast<const EdgeContact&>(ec));
    }
}
} // namespace

std::vector<int> ClothSystem::edges_in_contact(const Positions& X) const
{
    std::vector<int> out;
    for_each_edge_contact(*this, X, [&](const EdgeContact& c) { out.push_back(c.edge); });
    return out;
}

int ClothSystem::vertex_contact_count(const Positions& X) const
{
    int k = 0;
    for_each_contact(*this, X, [&](int, double, const Vec3&, const Collider&) { ++k; });
    return k;
}

void ClothSystem::update_static_friction(StaticFriction& sf, const Positions& X) const
{
    const int n = static_cast<int>(X.rows());
    if (static_cast<int>(sf.active.size()) != n) {
        sf.active.assign(static_cast<std::size_t>(n), 0);
        sf.anchor = Positions::Zero(n, 3);
        sf.lambda = Eigen::VectorXd::Zero(n);
        sf.normal = Positions::Zero(n, 3);
    }
    std::vector<char> touching(static_cast<std::size_t>(n), 0);
    for_each_contact(*this, X, [&](int i, double phi, const Vec3& nrm, const Collider&) {
        const auto k = static_cast<std::size_t>(i);
        if (!sf.active[k]) sf.anchor.row(i) = X.row(i);
        sf.active[k] = 1;
        touching[k] = 1;
        sf.lambda(i) = m_model.contact_stiffness(i) * (-phi);
        sf.normal.row(i) = nrm.transpose();
    });
    sf.contacts = 0;
    for (int i = 0; i < n; ++i) {
        const auto k = static_cast<std::size_t>(i);
        if (!touching[k]) sf.active[k] = 0;
        sf.contacts += sf.active[k];
    }
}

double ClothSystem::static_friction_term(int i, const Positions& X, Vec3* grad, Eigen::Matrix3d* hess) const
{
    const StaticFriction* sf = static_friction;
    if (!sf || !sf->active[static_cast<std::size_t>(i)] || m_model.friction <= 0) return 0;
    const double c = m_model.friction * sf->lambda(i), eps = sf->eps;
    const Vec3 nrm = sf->normal.row(i).transpose();
    const Eigen::Matrix3d P = Eigen::Matrix3d::Identity() - nrm * nrm.transpose();
    const Vec3 pu = P * (X.row(i) - sf->anchor.row(i)).transpose();
    const double y = pu.norm();
    const double e = y >= eps ? y : -y * y * y / (3 * eps * eps) + y * y / eps + eps / 3;
    // f1(y) / y, f1 = f0': 1/y beyond eps, 2/eps - y/eps^2 below (finite at 0).
    const double f1y = y >= eps ? 1 / y : 2 / eps - y / (eps * eps);
    if (grad) *grad = c * f1y * pu;
    if (hess) {
        // d/dx (f1/y P u) = f1/y P + (f1' y - f1)/y^3 (P u)(P u)^T, where
        // (f1' y - f1)/y^3 = -1/y^3 beyond eps and -1/(eps^2 y) below.
        *hess = c * f1y * P;
        if (y > 0) *hess -= c * (y >= eps ? 1 / (y * y * y) : 1 / (eps * eps * y)) * pu * pu.transpose();
    }
    return c * e;
}

double ClothSystem::potential_energy(const Positions& X) const
{
    ProfileScope timer(profile ? &profile->energy : nullptr);
    double e = 0;
    for (const auto& sp : m_model.springs) {
        double es, de, d2e;
        sp.law(m_model.spring_length(sp, X), es, de, d2e);
        e += es;
    }
    for (const auto& fb : m_model.fibers) {
        double es, de, d2e;
        fb.law(fb.vec(X).norm(), es, de, d2e);
        e += es;
    }
    const double beta = m_model.bend_stiffening, rho2 = m_model.bend_softening, peak2 = m_model.bend_peak;
    for (const auto& b : m_model.bends) {
        Vec3 s = Vec3::Zero();
        for (int a = 0; a < b.n; ++a) s += b.w[a] * X.row(b.v[a]).transpose();
        e += b.k * bend_law(s.squaredNorm(), b.quartic, beta, rho2, peak2).g;
    }
    for (int i = 0; i < X.rows(); ++i) e -= m_model.mass(i) * m_model.gravity.dot(X.row(i).transpose());
    for (const auto& a : m_model.anchors) {
        const Vec3 d = a.point(X) - a.target;
        e += 0.5 * a.k * (d.x() * d.x() + d.y() * d.y());
    }
    for_each_contact(*this, X, [&](int i, double phi, const Vec3&, const Collider&) { e += 0.5 * m_model.contact_stiffness(i) * phi * phi; });
    for_each_edge_contact(*this, X, [&](const EdgeContact& c) { e += 0.5 * c.k * c.phi * c.phi * c.w(); });
    for (const auto& p : self_contact_pairs(X)) e += self_contact_pair_energy(p, X);
    if (static_friction)
        for (int i = 0; i < X.rows(); ++i) e += static_friction_term(i, X);
    return e;
}

double ClothSystem::kinetic_energy(const Positions& V) const
{
    double e = 0;
    for (int i = 0; i < V.rows(); ++i) e += 0.5 * m_model.mass(i) * V.row(i).squaredNorm();
    return e;
}

Positions ClothSystem::gravity_forces() const
{
    Positions g(vertex_count(), 3);
    for (int i = 0; i < vertex_count(); ++i)
        g.row(i) = m_model.pinned[static_cast<std::size_t>(i)] ? Eigen::RowVector3d::Zero()
                                                                : Eigen::RowVector3d(m_model.mass(i) * m_model.gravity.transpose());
    return g;
}

void ClothSystem::conservative_forces(const Positions& X, Positions& f) const
{
    ProfileScope timer(profile ? &profile->forces : nullptr);
    f.setZero(X.rows(), 3);
    for (const auto& sp : m_model.springs) {
        if (sp.arc >= 0) {
            const SpringArc& arc = m_model.arcs[static_cast<std::size_t>(sp.arc)];
            ArcTerm t;
            if (!arc_term(arc, X, t)) continue;
            double es, de, d2e;
            sp.law(t.L, es, de, d2e);
            for (int p = 0; p < arc.n; ++p) f.row(arc.v[p]) -= (de * t.g[p]).transpose();
            continue;
        }
        const Vec3 u = X.row(sp.i) - X.row(sp.j);
        const double l = u.norm();
        if (l <= 1e-300) continue;
        double es, de, d2e;
        sp.law(l, es, de, d2e);
        const Vec3 fi = -de / l * u;
        f.row(sp.i) += fi.transpose();
        f.row(sp.j) -= fi.transpose();
    }
    for (const auto& fb : m_model.fibers) {
        const Vec3 u = fb.vec(X);
        const double l = u.norm();
        if (l <= 1e-300) continue;
        double es, de, d2e;
        fb.law(l, es, de, d2e);
        const Vec3 fu = -de / l * u;
        for (int a = 0; a < 3; ++a) f.row(fb.v[a]) += (fb.w[a] * fu).transpose();
    }
    const double beta = m_model.bend_stiffening, rho2 = m_model.bend_softening, peak2 = m_model.bend_peak;
    for (const auto& b : m_model.bends) {
        Vec3 s = Vec3::Zero();
        for (int a = 0; a < b.n; ++a) s += b.w[a] * X.row(b.v[a]).transpose();
        const BendLaw law = bend_law(s.squaredNorm(), b.quartic, beta, rho2, peak2);
        const double c = b.k * law.g1 * law.ds;
        for (int a = 0; a < b.n; ++a) f.row(b.v[a]) -= (c * b.w[a] * s).transpose();
    }
    for (int i = 0; i < X.rows(); ++i) f.row(i) += m_model.mass(i) * m_model.gravity.transpose();
    for (const auto& a : m_model.anchors) {
        const Vec3 d = a.point(X) - a.target;
        for (int i = 0; i < a.n; ++i) {
            const auto k = static_cast<std::size_t>(i);
            f(a.v[k], 0) -= a.k * a.w[k] * d.x();
            f(a.v[k], 1) -= a.k * a.w[k] * d.y();
        }
    }
    for_each_contact(*this, X, [&](int i, double phi, const Vec3& n, const Collider&) { f.row(i) -= (m_model.contact_stiffness(i) * phi * n).transpose(); });
    for_each_edge_contact(*this, X, [&](const EdgeContact& c) {
        // E = k phi^2 w / 2: grad = k phi w grad(phi) + k phi^2 grad(w) / 2,
        // grad(phi) = ((1-t) n, t n) (Danskin), grad(da) = (n_a, 0) - grad(phi).
        const auto& ed = m_edges[static_cast<std::size_t>(c.edge)];
        Eigen::Matrix<double, 6, 1> grad;
        edge_gradients(c, grad);
        f.row(ed[0]) -= (c.k * grad.head<3>()).transpose();
        f.row(ed[1]) -= (c.k * grad.tail<3>()).transpose();
    });
    for (const auto& p : self_contact_pairs(X)) {
        Vec12 g;
        self_contact_pair_energy(p, X, &g);
        for (int a = 0; a < 4; ++a) f.row(p.v[static_cast<std::size_t>(a)]) -= g.segment<3>(3 * a).transpose();
    }
    if (static_friction)
        for (int i = 0; i < X.rows(); ++i) {
            Vec3 g;
            if (static_friction_term(i, X, &g) != 0) f.row(i) -= g.transpose();
        }
}

void ClothSystem::add_damping_forces(const Positions& X, const Positions& V, Positions& f) const
{
    for (const auto& sp : m_model.springs) {
        if (sp.d == 0) continue;
        Vec3 u = X.row(sp.i) - X.row(sp.j);
        const double l = u.norm();
        if (l <= 1e-300) continue;
        u /= l;
        const double rate = (V.row(sp.i) - V.row(sp.j)).dot(u.transpose());
        const Vec3 fi = -sp.d * rate * u;
        f.row(sp.i) += fi.transpose();
        f.row(sp.j) -= fi.transpose();
    }
    for (const auto& fb : m_model.fibers) {
        if (fb.d == 0) continue;
        Vec3 u = fb.vec(X);
        const double l = u.norm();
        if (l <= 1e-300) continue;
        u /= l;
        const double rate = fb.vec(V).dot(u);
        for (int a = 0; a < 3; ++a) f.row(fb.v[a]) -= (fb.d * rate * fb.w[a] * u).transpose();
    }
    for (const auto& b : m_model.bends) {
        if (b.d == 0) continue;
        Vec3 s = Vec3::Zero();
        for (int a = 0; a < b.n; ++a) s += b.w[a] * V.row(b.v[a]).transpose();
        for (int a = 0; a < b.n; ++a) f.row(b.v[a]) -= (b.d * b.w[a] * s).transpose();
    }
    if (m_model.air_damping > 0)
        for (int i = 0; i < X.rows(); ++i) f.row(i) -= m_model.air_damping * m_model.mass(i) * V.row(i);
}

void ClothSystem::add_friction_forces(const Positions& X, const Positions& V, Positions& f, double v_eps) const
{
    if (m_model.friction <= 0) return;
    const double mu = m_model.friction;
    for_each_contact(*this, X, [&](int i, double phi, const Vec3& n, const Collider&) {
        const double N = m_model.contact_stiffness(i) * (-phi);
        const Vec3 vi = V.row(i).transpose();
        const Vec3 vt = vi - vi.dot(n) * n;
        const double s = std::sqrt(vt.squaredNorm() + v_eps * v_eps);
        f.row(i) -= (mu * N / s * vt).transpose();
    });
}

void ClothSystem::total_forces(const Positions& X, const Positions& V, Positions& f) const
{
    ++force_evaluations;
    conservative_forces(X, f);
    add_damping_forces(X, V, f);
    add_friction_forces(X, V, f);
    for (int i = 0; i < X.rows(); ++i)
        if (m_model.pinned[static_cast<std::size_t>(i)]) f.row(i).setZero();
}

// ---- Hessian ----------------------------------------------------------------

HessianAssembler::HessianAssembler(const ClothSystem& s) : m_s(s) { build_pattern(); }

void HessianAssembler::build_pattern()
{
    const ClothSystem& s = m_s;
    const int n = s.vertex_count();
    const auto& m = s.model();
    m_nbr.assign(static_cast<std::size_t>(n), {});
    auto link = [&](int a, int b) {
        if (a > b) std::swap(a, b);
        m_nbr[static_cast<std::size_t>(b)].push_back(a);
    };
    for (int i = 0; i < n; ++i) link(i, i);
    for (const auto& sp : m.springs) {
        link(sp.i, sp.j);
        if (sp.arc < 0) continue;
        const SpringArc& arc = m.arcs[static_cast<std::size_t>(sp.arc)];
        for (int p = 0; p < arc.n; ++p)
            for (int q = p + 1; q < arc.n; ++q) link(arc.v[p], arc.v[q]);
    }
    for (const auto& fb : m.fibers)
        for (int p = 0; p < 3; ++p)
            for (int q = p + 1; q < 3; ++q) link(fb.v[p], fb.v[q]);
    for (const auto& b : m.bends)
        for (int p = 0; p < b.n; ++p)
            for (int q = p + 1; q < b.n; ++q) link(b.v[p], b.v[q]);
    for (const auto& e : s.edges()) link(e[0], e[1]);
    for (const auto& a : m.anchors)
        for (int p = 0; p < a.n; ++p)
            for (int q = p + 1; q < a.n; ++q) link(a.v[static_cast<std::size_t>(p)], a.v[static_cast<std::size_t>(q)]);
    for (const auto& e : m_extra) link(e.first, e.second);
    std::vector<int> colptr(static_cast<std::size_t>(3 * n + 1), 0);
    long nnz = 0;
    for (int j = 0; j < n; ++j) {
        auto& nb = m_nbr[static_cast<std::size_t>(j)];
        std::sort(nb.begin(), nb.end());
        nb.erase(std::unique(nb.begin(), nb.end()), nb.end());
        // Column 3j+b holds 3 rows per off-diagonal neighbour and b+1 rows of the diagonal block (last).
        for (int b = 0; b < 3; ++b) {
            colptr[static_cast<std::size_t>(3 * j + b)] = static_cast<int>(nnz);
            nnz += 3 * static_cast<long>(nb.size() - 1) + b + 1;
        }
    }
    colptr[static_cast<std::size_t>(3 * n)] = static_cast<int>(nnz);
    m_H.resize(3 * n, 3 * n);
    m_H.resizeNonZeros(nnz);
    std::copy(colptr.begin(), colptr.end(), m_H.outerIndexPtr());
    int* rows = m_H.innerIndexPtr();
    for (int j = 0; j < n; ++j) {
        const auto& nb = m_nbr[static_cast<std::size_t>(j)];
        for (int b = 0; b < 3; ++b) {
            int k = colptr[static_cast<std::size_t>(3 * j + b)];
            for (int i : nb) {
                const int nrows = i == j ? b + 1 : 3;
                for (int a = 0; a < nrows; ++a) rows[k++] = 3 * i + a;
            }
        }
    }
    m_H.valuePtr()[0] = 0; // pattern is final; values are written by assemble()
    m_spring_blocks.clear();
    m_diag_blocks.clear();
    m_bend_blocks.clear();
    m_bend_offset.clear();
    m_edge_blocks.clear();
    m_spring_blocks.reserve(m.springs.size());
    for (const auto& sp : m.springs) m_spring_blocks.push_back(block(std::min(sp.i, sp.j), std::max(sp.i, sp.j)));
    m_diag_blocks.reserve(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) m_diag_blocks.push_back(block(i, i));
    m_bend_offset.reserve(m.bends.size());
    for (const auto& b : m.bends) {
        m_bend_offset.push_back(m_bend_blocks.size());
        for (int p = 0; p < b.n; ++p)
            for (int q = p + 1; q < b.n; ++q) m_bend_blocks.push_back(block(std::min(b.v[p], b.v[q]), std::max(b.v[p], b.v[q])));
    }
    m_edge_blocks.reserve(s.edges().size());
    for (const auto& e : s.edges()) m_edge_blocks.push_back(block(e[0], e[1]));
    m_arc_blocks.clear();
    m_arc_offset.assign(m.springs.size(), 0);
    for (std::size_t sp = 0; sp < m.springs.size(); ++sp) {
        if (m.springs[sp].arc < 0) continue;
        m_arc_offset[sp] = m_arc_blocks.size();
        const SpringArc& arc = m.arcs[static_cast<std::size_t>(m.springs[sp].arc)];
        for (int p = 0; p < arc.n; ++p)
            for (int q = p + 1; q < arc.n; ++q) m_arc_blocks.push_back(block(std::min(arc.v[p], arc.v[q]), std::max(arc.v[p], arc.v[q])));
    }
    m_fiber_blocks.clear();
    m_fiber_blocks.reserve(3 * m.fibers.size());
    for (const auto& fb : m.fibers)
        for (int p = 0; p < 3; ++p)
            for (int q = p + 1; q < 3; ++q) m_fiber_blocks.push_back(block(std::min(fb.v[p], fb.v[q]), std::max(fb.v[p], fb.v[q])));
}

bool HessianAssembler::has_block(int i, int j) const
{
    const auto& nb = m_nbr[static_cast<std::size_t>(j)];
    return std::binary_search(nb.begin(), nb.end(), i);
}

HessianAssembler::Block HessianAssembler::block(int i, int j) const
{
    const auto& nb = m_nbr[static_cast<std::size_t>(j)];
    const int pos = static_cast<int>(std::lower_bound(nb.begin(), nb.end(), i) - nb.begin());
    Block bl{};
    for (int b = 0; b < 3; ++b) bl.col[b] = m_H.outerIndexPtr()[3 * j + b] + 3 * pos;
    return bl;
}

namespace {

/// The stiffness of an axial element (a spring, a membrane fibre) of current
/// vector u: E''(l) along it, E'(l) / l across it (negative in compression: the
/// projected form drops it), and its dashpot along it. false: zero length.
template <class Element>
bool axial_stiffness(Vec3 u, const Element& element, bool project, double damping_scale, Eigen::Matrix3d& K)
{
    const double l = u.norm();
    if (l <= 1e-300) return false;
    u /= l;
    const Eigen::Matrix3d nn = u * u.transpose();
    double es, de, d2e;
    element.law(l, es, de, d2e);
    double t = de / l;
    if (project && t < 0) t = 0;
    K = d2e * nn + t * (Eigen::Matrix3d::Identity() - nn);
    if (damping_scale != 0) K += damping_scale * element.d * nn;
    return true;
}

} // namespace

void HessianAssembler::add_diag(const Block& bl, const Eigen::Matrix3d& K)
{
    double* val = m_H.valuePtr();
    for (int b = 0; b < 3; ++b)
        for (int a = 0; a <= b; ++a) val[bl.col[b] + a] += K(a, b);
}

void HessianAssembler::add_off(const Block& bl, const Eigen::Matrix3d& K)
{
    double* val = m_H.valuePtr();
    for (int b = 0; b < 3; ++b)
        for (int a = 0; a < 3; ++a) val[bl.col[b] + a] += K(a, b);
}

void HessianAssembler::grow_pattern(const std::vector<ProximityPair>& self_pairs)
{
    std::vector<std::pair<int, int>> missing;
    for (const auto& p : self_pairs)
        for (int a = 0; a < 4; ++a)
            for (int b = a + 1; b < 4; ++b) {
                const int i = std::min(p.v[static_cast<std::size_t>(a)], p.v[static_cast<std::size_t>(b)]);
                const int j = std::max(p.v[static_cast<std::size_t>(a)], p.v[static_cast<std::size_t>(b)]);
                if (!has_block(i, j)) missing.emplace_back(i, j);
            }
    if (missing.empty()) return;
    m_extra.insert(m_extra.end(), missing.begin(), missing.end());
    std::sort(m_extra.begin(), m_extra.end());
    m_extra.erase(std::unique(m_extra.begin(), m_extra.end()), m_extra.end());
    build_pattern();
    ++m_revision;
}

void HessianAssembler::add_springs(const Positions& X, double damping_scale, bool project_springs)
{
    const auto& m = m_s.model();
    const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
    for (std::size_t s = 0; s < m.springs.size(); ++s) {
        const auto& sp = m.springs[s];
        if (sp.arc >= 0) {
            // E(L) with L the arc (SpringArc): E'' grad L grad L^T + E' hess L, where
            // hess L = (I - u u^T) / l on the chord's ends (minus between them) plus
            // 2 c_e w_p w_q I of each end's curvature; E' < 0 (compression) makes the
            // second part negative, and the projected form drops it, as for a spring.
            const SpringArc& arc = m.arcs[static_cast<std::size_t>(sp.arc)];
            ArcTerm t;
            if (!arc_term(arc, X, t)) continue;
            double es, de, d2e;
            sp.law(t.L, es, de, d2e);
            const double dl = project_springs && de < 0 ? 0.0 : de;
            const Eigen::Matrix3d chord = dl / t.l * (I - t.u * t.u.transpose()) + damping_scale * sp.d * t.u * t.u.transpose();
            auto Kpq = [&](int p, int q) {
                Eigen::Matrix3d K = d2e * t.g[p] * t.g[q].transpose();
                K.diagonal().array() += 2 * dl * (arc.c[0] * arc.w[0][p] * arc.w[0][q] + arc.c[1] * arc.w[1][p] * arc.w[1][q]);
                if (p < 2 && q < 2) K += (p == q ? 1.0 : -1.0) * chord;
                return K;
            };
            for (int p = 0; p < arc.n; ++p) add_diag(m_diag_blocks[static_cast<std::size_t>(arc.v[p])], Kpq(p, p));
            std::size_t b = m_arc_offset[s];
            for (int p = 0; p < arc.n; ++p)
                for (int q = p + 1; q < arc.n; ++q, ++b) {
                    // Off-diagonal blocks are stored once, rows of the smaller vertex.
                    if (arc.v[p] < arc.v[q]) add_off(m_arc_blocks[b], Kpq(p, q));
                    else add_off(m_arc_blocks[b], Kpq(q, p));
                }
            continue;
        }
        Eigen::Matrix3d K;
        if (!axial_stiffness(X.row(sp.i) - X.row(sp.j), sp, project_springs, damping_scale, K)) continue;
        add_diag(m_diag_blocks[static_cast<std::size_t>(sp.i)], K);
        add_diag(m_diag_blocks[static_cast<std::size_t>(sp.j)], K);
        add_off(m_spring_blocks[s], -K);
    }
}

void HessianAssembler::add_fibers(const Positions& X, double damping_scale, bool project_springs)
{
    const auto& m = m_s.model();
    for (std::size_t s = 0; s < m.fibers.size(); ++s) {
        // As a spring's, in the fibre's vector d = sum w_a x_a; vertex blocks w_a w_b K.
        const auto& fb = m.fibers[s];
        Eigen::Matrix3d K;
        if (!axial_stiffness(fb.vec(X), fb, project_springs, damping_scale, K)) continue;
        for (int p = 0; p < 3; ++p) add_diag(m_diag_blocks[static_cast<std::size_t>(fb.v[p])], fb.w[p] * fb.w[p] * K);
        std::size_t b = 3 * s;
        // Off-diagonal blocks are stored once, (min, max); K is symmetric.
        for (int p = 0; p < 3; ++p)
            for (int q = p + 1; q < 3; ++q, ++b) add_off(m_fiber_blocks[b], fb.w[p] * fb.w[q] * K);
    }
}

void HessianAssembler::add_bends(const Positions& X, double damping_scale)
{
    const auto& m = m_s.model();
    const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
    const double beta = m.bend_stiffening, rho2 = m.bend_softening, peak2 = m.bend_peak;
    for (std::size_t s = 0; s < m.bends.size(); ++s) {
        const auto& b = m.bends[s];
        // The Hessian in d of bend_law's energy; vertex blocks are w_p w_q times it.
        Eigen::Matrix3d Kd = (b.k + damping_scale * b.d) * I;
        if (beta > 0 || rho2 > 0 || peak2 > 0 || b.quartic > 0) {
            Vec3 d = Vec3::Zero();
            for (int a = 0; a < b.n; ++a) d += b.w[a] * X.row(b.v[a]).transpose();
            const BendLaw law = bend_law(d.squaredNorm(), b.quartic, beta, rho2, peak2);
            const double c = law.g1 * law.ds, c1 = law.g2 * law.ds * law.ds + law.g1 * b.quartic;
            Kd += b.k * ((c - 1.0) * I + 2.0 * c1 * d * d.transpose());
        }
        for (int p = 0; p < b.n; ++p) add_diag(m_diag_blocks[static_cast<std::size_t>(b.v[p])], b.w[p] * b.w[p] * Kd);
        std::size_t t = m_bend_offset[s];
        for (int p = 0; p < b.n; ++p)
            for (int q = p + 1; q < b.n; ++q, ++t) add_off(m_bend_blocks[t], b.w[p] * b.w[q] * Kd);
    }
}

void HessianAssembler::add_diagonal(const Eigen::VectorXd& extra_diag, double damping_scale)
{
    const auto& m = m_s.model();
    const int n = m_s.vertex_count();
    for (int i = 0; i < n; ++i) {
        double d = extra_diag.size() ? extra_diag(i) : 0.0;
        if (damping_scale != 0) d += damping_scale * m.air_damping * m.mass(i);
        if (d != 0) add_diag(m_diag_blocks[static_cast<std::size_t>(i)], d * Eigen::Matrix3d::Identity());
    }
}

void HessianAssembler::add_anchors()
{
    for (const auto& a : m_s.model().anchors) {
        Eigen::Matrix3d P = Eigen::Matrix3d::Zero();
        P(0, 0) = P(1, 1) = a.k;
        for (int i = 0; i < a.n; ++i) {
            const auto ki = static_cast<std::size_t>(i);
            add_diag(m_diag_blocks[static_cast<std::size_t>(a.v[ki])], a.w[ki] * a.w[ki] * P);
            for (int j = i + 1; j < a.n; ++j) {
                const auto kj = static_cast<std::size_t>(j);
                // Off-diagonal blocks are stored once, (min, max); P is symmetric.
                add_off(block(std::min(a.v[ki], a.v[kj]), std::max(a.v[ki], a.v[kj])), a.w[ki] * a.w[kj] * P);
            }
        }
    }
}

void HessianAssembler::add_contacts(const Positions& X, bool project_contacts)
{
    const auto& m = m_s.model();
    for_each_contact(m_s, X, [&](int i, double phi, const Vec3& nrm, const Collider& c) {
        Eigen::Matrix3d K = nrm * nrm.transpose();
        // Exact: the normal turns as the point moves (curved collider surfaces);
        // with phi < 0 this term is negative, so the projected form drops it.
        if (!project_contacts) K += phi * c.distance_hessian(X.row(i).transpose());
        add_diag(m_diag_blocks[static_cast<std::size_t>(i)], m.contact_stiffness(i) * K);
    });
    for_each_edge_contact(m_s, X, [&](const EdgeContact& c) {
        // E = k phi^2 w / 2 with phi(x_a, x_b) = min_t d((1-t) x_a + t x_b) - offset
        // (see edge_gradients); the projected form keeps k w grad(phi) grad(phi)^T only.
        const auto& ed = m_s.edges()[static_cast<std::size_t>(c.edge)];
        Eigen::Matrix<double, 6, 1> grad;
        Eigen::Matrix<double, 6, 6> K;
        edge_gradients(c, grad, &K, !project_contacts);
        K *= c.k;
        add_diag(m_diag_blocks[static_cast<std::size_t>(ed[0])], K.block<3, 3>(0, 0));
        add_diag(m_diag_blocks[static_cast<std::size_t>(ed[1])], K.block<3, 3>(3, 3));
        add_off(m_edge_blocks[static_cast<std::size_t>(c.edge)], K.block<3, 3>(0, 3));
    });
}

void HessianAssembler::add_self_contacts(const std::vector<ProximityPair>& self_pairs, const Positions& X, bool project_contacts)
{
    for (const auto& p : self_pairs) {
        Mat12 K;
        m_s.self_contact_pair_energy(p, X, nullptr, &K);
        if (project_contacts) {
            // The barrier's own Hessian, projected to positive semidefinite as IPC does.
            Eigen::SelfAdjointEigenSolver<Mat12> es(K);
            K = es.eigenvectors() * es.eigenvalues().cwiseMax(0.0).asDiagonal() * es.eigenvectors().transpose();
        }
        for (int a = 0; a < 4; ++a)
            for (int b = a; b < 4; ++b) {
                const int i = p.v[static_cast<std::size_t>(a)], j = p.v[static_cast<std::size_t>(b)];
                const Eigen::Matrix3d Kab = K.block<3, 3>(3 * a, 3 * b);
                if (a == b) add_diag(m_diag_blocks[static_cast<std::size_t>(i)], Kab);
                else if (i < j) add_off(block(i, j), Kab);
                else add_off(block(j, i), Kab.transpose());
            }
    }
}

void HessianAssembler::pin_rows()
{
    const auto& m = m_s.model();
    bool any_pinned = false;
    for (char p : m.pinned) any_pinned |= p != 0;
    if (!any_pinned) return;
    double* val = m_H.valuePtr();
    const int* outer = m_H.outerIndexPtr();
    const int* inner = m_H.innerIndexPtr();
    for (int col = 0; col < 3 * m_s.vertex_count(); ++col) {
        const bool pc = m.pinned[static_cast<std::size_t>(col / 3)] != 0;
        for (int k = outer[col]; k < outer[col + 1]; ++k) {
            const int row = inner[k];
            if (pc || m.pinned[static_cast<std::size_t>(row / 3)]) val[k] = row == col ? 1.0 : 0.0;
        }
    }
}

void HessianAssembler::assemble(const Positions& X, const Eigen::VectorXd& extra_diag, double damping_scale, Projection projection)
{
    const bool project = projection == Projection::All;
    // Self-contact pairs couple vertices the mesh does not: grow the pattern
    // first (outside the timer: the search is timed as self-contact).
    const auto& self_pairs = m_s.self_contact_pairs(X);
    grow_pattern(self_pairs);
    ProfileScope timer(m_s.profile ? &m_s.profile->assemble : nullptr);
    double* val = m_H.valuePtr();
    std::fill(val, val + m_H.nonZeros(), 0.0);
    add_springs(X, damping_scale, project);
    add_fibers(X, damping_scale, project);
    add_bends(X, damping_scale);
    add_diagonal(extra_diag, damping_scale);
    add_anchors();
    add_contacts(X, project);
    add_self_contacts(self_pairs, X, project);
    if (m_s.static_friction)
        for (int i = 0; i < m_s.vertex_count(); ++i) {
            Eigen::Matrix3d K;
            if (m_s.static_friction_term(i, X, nullptr, &K) != 0) add_diag(m_diag_blocks[static_cast<std::size_t>(i)], K);
        }
    // Pinned vertices: identity rows and columns (their update is zero).
    pin_rows();
}

} // namespace drape::cloth
