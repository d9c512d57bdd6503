#include "engine/cloth/self_contact.hpp"

#include "engine/cloth/bvh.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <tuple>

namespace drape::cloth {

using Vec3 = Eigen::Vector3d;

namespace {

/// The closest feature of one side of a pair: up to three of the pair's four
/// vertices (local indices) with the barycentric weights of the closest point.
struct Feature {
    int n = 0;
    int idx[3] = {0, 0, 0};
    double w[3] = {0, 0, 0};
};

Feature vertex_feature(int a)
{
    Feature f;
    f.n = 1;
    f.idx[0] = a;
    f.w[0] = 1;
    return f;
}

/// Feature of a segment (local vertices a, b) at parameter t in [0, 1].
Feature segment_feature(int a, int b, double t)
{
    if (t <= 0) return vertex_feature(a);
    if (t >= 1) return vertex_feature(b);
    Feature f;
    f.n = 2;
    f.idx[0] = a;
    f.idx[1] = b;
    f.w[0] = 1 - t;
    f.w[1] = t;
    return f;
}

double segment_parameter(const Vec3& p, const Vec3& a, const Vec3& b)
{
    const Vec3 e = b - a;
    const double ee = e.squaredNorm();
    if (!(ee > 0)) return 0;
    return std::clamp((p - a).dot(e) / ee, 0.0, 1.0);
}

/// Closest feature of the triangle (local vertices 1, 2, 3) to the point x[0]
/// (Ericson, Real-Time Collision Detection, 5.1.5: Voronoi regions).
Feature triangle_feature(const std::array<Vec3, 4>& x)
{
    const Vec3 &p = x[0], &a = x[1], &b = x[2], &c = x[3];
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = ab.dot(ap), d2 = ac.dot(ap);
    if (d1 <= 0 && d2 <= 0) return vertex_feature(1);
    const Vec3 bp = p - b;
    const double d3 = ab.dot(bp), d4 = ac.dot(bp);
    if (d3 >= 0 && d4 <= d3) return vertex_feature(2);
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return segment_feature(1, 2, d1 / (d1 - d3));
    const Vec3 cp = p - c;
    const double d5 = ab.dot(cp), d6 = ac.dot(cp);
    if (d6 >= 0 && d5 <= d6) return vertex_feature(3);
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return segment_feature(1, 3, d2 / (d2 - d6));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return segment_feature(2, 3, (d4 - d3) / ((d4 - d3) + (d5 - d6)));
    const double sum = va + vb + vc;
    if (!(sum > 1e-30 * (ab.squaredNorm() * ac.squaredNorm()) && sum > 0)) {
        // A degenerate (needle) triangle: the nearest of its edges.
        Feature best;
        double best_d = std::numeric_limits<double>::infinity();
        const int E[3][2] = {{1, 2}, {1, 3}, {2, 3}};
        for (const auto& e : E) {
            const double t = segment_parameter(p, x[e[0]], x[e[1]]);
            const double d = (p - ((1 - t) * x[e[0]] + t * x[e[1]])).squaredNorm();
            if (d < best_d) {
                best_d = d;
                best = segment_feature(e[0], e[1], t);
            }
        }
        return best;
    }
    Feature f;
    f.n = 3;
    f.idx[0] = 1;
    f.idx[1] = 2;
    f.idx[2] = 3;
    f.w[1] = vb / sum;
    f.w[2] = vc / sum;
    f.w[0] = 1 - f.w[1] - f.w[2];
    return f;
}

/// Closest parameters of two segments x0-x1 and x2-x3 (Ericson 5.1.9). Nearly
/// parallel segments take s = 0 (an end point against the other segment).
std::pair<Feature, Feature> edge_features(const std::array<Vec3, 4>& x)
{
    const Vec3 d1 = x[1] - x[0], d2 = x[3] - x[2], r = x[0] - x[2];
    const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
    double s = 0, t = 0;
    if (a <= 1e-30 && e <= 1e-30) {
        s = t = 0;
    } else if (a <= 1e-30) {
        s = 0;
        t = std::clamp(f / e, 0.0, 1.0);
    } else {
        const double c = d1.dot(r);
        if (e <= 1e-30) {
            t = 0;
            s = std::clamp(-c / a, 0.0, 1.0);
        } else {
            const double b = d1.dot(d2), denom = a * e - b * b;
            s = denom > 1e-12 * a * e ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
            t = (b * s + f) / e;
            if (t < 0) {
                t = 0;
                s = std::clamp(-c / a, 0.0, 1.0);
            } else if (t > 1) {
                t = 1;
                s = std::clamp((b - c) / a, 0.0, 1.0);
            }
        }
    }
    return {segment_feature(0, 1, s), segment_feature(2, 3, t)};
}

/// s = |r|^2 with r = sum_A w x - sum_B w x, and the derivatives of the
/// envelope min over the features' free weights: with r = sum_v c_v(w) x_v (c
/// affine in the free weights w), grad_v = 2 c_v r and
/// Hess = 2 (c c^T) (x) I - F W^-1 F^T, F_k = d/dw_k grad, W = d2s/dw2.
double envelope(const std::array<Vec3, 4>& x, const Feature& A, const Feature& B, Vec12* grad, Mat12* hess)
{
    Eigen::Vector4d c = Eigen::Vector4d::Zero();
    for (int i = 0; i < A.n; ++i) c(A.idx[i]) += A.w[i];
    for (int i = 0; i < B.n; ++i) c(B.idx[i]) -= B.w[i];
    Vec3 r = Vec3::Zero();
    for (int v = 0; v < 4; ++v) r += c(v) * x[static_cast<std::size_t>(v)];
    const double s = r.squaredNorm();
    if (grad)
        for (int v = 0; v < 4; ++v) grad->segment<3>(3 * v) = 2 * c(v) * r;
    if (!hess) return s;
    Mat12& H = *hess;
    H.setZero();
    for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) H.block<3, 3>(3 * a, 3 * b).diagonal().setConstant(2 * c(a) * c(b));
    // The free weights: every vertex of a feature after its first (the first's
    // weight is one minus the others').
    Eigen::Vector4d dc[2];
    int m = 0;
    for (int i = 1; i < A.n; ++i, ++m) {
        dc[m].setZero();
        dc[m](A.idx[i]) += 1;
        dc[m](A.idx[0]) -= 1;
    }
    for (int i = 1; i < B.n; ++i, ++m) {
        dc[m].setZero();
        dc[m](B.idx[i]) -= 1;
        dc[m](B.idx[0]) += 1;
    }
    if (m == 0) return s;
    Eigen::Matrix<double, 12, 2> Fm;
    Eigen::Matrix2d W;
    Vec3 R[2];
    for (int k = 0; k < m; ++k) {
        R[k].setZero();
        for (int v = 0; v < 4; ++v) R[k] += dc[k](v) * x[static_cast<std::size_t>(v)];
        for (int v = 0; v < 4; ++v) Fm.block<3, 1>(3 * v, k) = 2 * (c(v) * R[k] + dc[k](v) * r);
    }
    for (int j = 0; j < m; ++j)
        for (int k = 0; k < m; ++k) W(j, k) = 2 * R[j].dot(R[k]);
    if (m == 1) {
        if (W(0, 0) > 0) H -= Fm.col(0) * Fm.col(0).transpose() / W(0, 0);
    } else {
        const double det = W(0, 0) * W(1, 1) - W(0, 1) * W(1, 0);
        if (det > 1e-14 * W(0, 0) * W(1, 1)) H -= Fm * W.inverse() * Fm.transpose();
    }
    return s;
}

/// c = |e_a x e_b|^2 of the edges x1 - x0 and x3 - x2, with gradient and Hessian.
double cross_norm2(const std::array<Vec3, 4>& x, Vec12* grad, Mat12* hess)
{
    const Vec3 u = x[1] - x[0], v = x[3] - x[2];
    const double uu = u.squaredNorm(), vv = v.squaredNorm(), uv = u.dot(v);
    const double c = uu * vv - uv * uv;
    if (grad || hess) {
        const Vec3 gu = 2 * vv * u - 2 * uv * v, gv = 2 * uu * v - 2 * uv * u;
        if (grad) *grad << -gu, gu, -gv, gv;
        if (hess) {
            const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
            const Eigen::Matrix3d Huu = 2 * vv * I - 2 * v * v.transpose(), Hvv = 2 * uu * I - 2 * u * u.transpose();
            const Eigen::Matrix3d Huv = 4 * u * v.transpose() - 2 * v * u.transpose() - 2 * uv * I;
            const double sg[4] = {-1, 1, -1, 1};
            for (int a = 0; a < 4; ++a)
                for (int b = 0; b < 4; ++b) {
                    const Eigen::Matrix3d& K = a < 2 ? (b < 2 ? Huu : Huv) : (b < 2 ? Eigen::Matrix3d(Huv.transpose()) : Hvv);
                    hess->block<3, 3>(3 * a, 3 * b) = sg[a] * sg[b] * K;
                }
        }
    }
    return c;
}

} // namespace

double pair_squared_distance(ProximityPair::Kind kind, const std::array<Vec3, 4>& x, Vec12* grad, Mat12* hess)
{
    if (kind == ProximityPair::PointTriangle) return envelope(x, vertex_feature(0), triangle_feature(x), grad, hess);
    const auto [A, B] = edge_features(x);
    return envelope(x, A, B, grad, hess);
}

double pair_energy(ProximityPair::Kind kind, const std::array<Vec3, 4>& x, double k, double d_hat, double eps_cross,
                   Vec12* grad, Mat12* hess)
{
    if (grad) grad->setZero();
    if (hess) hess->setZero();
    const double s_hat = d_hat * d_hat;
    Vec12 gs;
    Mat12 Hs;
    const double s = pair_squared_distance(kind, x, grad || hess ? &gs : nullptr, hess ? &Hs : nullptr);
    if (s >= s_hat) return 0;
    if (!(s > 0)) return std::numeric_limits<double>::infinity();
    const double u = s / s_hat, lu = std::log(u), um = u - 1;
    const double beta = -um * um * lu;
    const double b1 = -2 * um * lu - um * um / u;
    const double b2 = -2 * lu - 4 * um / u + um * um / (u * u);
    const double E = 0.5 * k * s_hat * beta, dE = 0.5 * k * b1, d2E = 0.5 * k * b2 / s_hat;
    double mol = 1, m1 = 0, m2 = 0, cval = 0;
    Vec12 gc;
    Mat12 Hc;
    if (kind == ProximityPair::EdgeEdge && eps_cross > 0) {
        cval = cross_norm2(x, grad || hess ? &gc : nullptr, hess ? &Hc : nullptr);
        if (cval < eps_cross) {
            const double q = cval / eps_cross;
            mol = (2 - q) * q;
            m1 = (2 - 2 * q) / eps_cross;
            m2 = -2 / (eps_cross * eps_cross);
        }
    }
    const bool mollified = m1 != 0 || m2 != 0 || mol != 1;
    if (grad) {
        *grad = mol * dE * gs;
        if (mollified) *grad += E * m1 * gc;
    }
    if (hess) {
        *hess = mol * (d2E * gs * gs.transpose() + dE * Hs);
        if (mollified) {
            const Vec12 gm = m1 * gc, gE = dE * gs;
            *hess += E * (m2 * gc * gc.transpose() + m1 * Hc) + gm * gE.transpose() + gE * gm.transpose();
        }
    }
    return mol * E;
}

SelfContact::SelfContact() = default;
SelfContact::~SelfContact() = default;
SelfContact::SelfContact(const Triangles& F, const std::vector<std::array<int, 2>>& edges, const Positions& rest)
    : m_F(F), m_edges(edges), m_rest(rest)
{
}
SelfContact::SelfContact(const SelfContact& o) : m_F(o.m_F), m_edges(o.m_edges), m_rest(o.m_rest) {}
SelfContact& SelfContact::operator=(const SelfContact& o)
{
    if (this == &o) return *this;
    m_F = o.m_F;
    m_edges = o.m_edges;
    m_rest = o.m_rest;
    m_list = List{};
    m_cache = Cache{};
    m_tri_bvh.reset();
    m_edge_bvh.reset();
    searches = 0;
    return *this;
}

double SelfContact::eps_cross(const ProximityPair& p) const
{
    if (p.kind != ProximityPair::EdgeEdge) return 0;
    const double la = (m_rest.row(p.v[1]) - m_rest.row(p.v[0])).squaredNorm();
    const double lb = (m_rest.row(p.v[3]) - m_rest.row(p.v[2])).squaredNorm();
    return 1e-3 * la * lb;
}

namespace {

std::array<Vec3, 4> gather(const Positions& X, const std::array<int, 4>& v)
{
    return {X.row(v[0]).transpose(), X.row(v[1]).transpose(), X.row(v[2]).transpose(), X.row(v[3]).transpose()};
}

bool shares_vertex(const std::array<int, 2>& a, const std::array<int, 2>& b)
{
    return a[0] == b[0] || a[0] == b[1] || a[1] == b[0] || a[1] == b[1];
}


/// The skin of the candidate list [m]: large enough that a Newton iteration
/// near rest (micrometres) never rebuilds it, small enough that a flat mesh's
/// neighbours (an altitude of a triangle away) stay off it.
double skin_of(double d_hat) { return std::max(4 * d_hat, 2e-3); }

bool all_pinned(const std::vector<char>& pinned, const std::array<int, 4>& v)
{
    if (pinned.empty()) return false;
    for (int i : v)
        if (!pinned[static_cast<std::size_t>(i)]) return false;
    return true;
}

} // namespace

template <class F>
void SelfContact::search(const std::vector<detail::Box>& vbox, double pad, F&& f) const
{
    std::vector<detail::Box> tbox(static_cast<std::size_t>(m_F.rows())), ebox(m_edges.size());
    for (Eigen::Index t = 0; t < m_F.rows(); ++t) {
        for (int k = 0; k < 3; ++k) tbox[static_cast<std::size_t>(t)].add(vbox[static_cast<std::size_t>(m_F(t, k))]);
        tbox[static_cast<std::size_t>(t)].inflate(pad);
    }
    for (std::size_t e = 0; e < m_edges.size(); ++e) {
        for (int k = 0; k < 2; ++k) ebox[e].add(vbox[static_cast<std::size_t>(m_edges[e][static_cast<std::size_t>(k)])]);
        ebox[e].inflate(0.5 * pad);
    }
    const detail::Bvh& tb = refit(m_tri_bvh, std::move(tbox));
    const detail::Bvh& eb = refit(m_edge_bvh, std::move(ebox));
    for (int i = 0; i < static_cast<int>(vbox.size()); ++i)
        tb.query(vbox[static_cast<std::size_t>(i)], [&](int t) {
            if (m_F(t, 0) == i || m_F(t, 1) == i || m_F(t, 2) == i) return;
            f(ProximityPair{ProximityPair::PointTriangle, {i, m_F(t, 0), m_F(t, 1), m_F(t, 2)}});
        });
    eb.self_pairs([&](int a, int b) {
        const auto& ea = m_edges[static_cast<std::size_t>(std::min(a, b))];
        const auto& eb2 = m_edges[static_cast<std::size_t>(std::max(a, b))];
        if (shares_vertex(ea, eb2)) return;
        f(ProximityPair{ProximityPair::EdgeEdge, {ea[0], ea[1], eb2[0], eb2[1]}});
    });
}

const detail::Bvh& SelfContact::refit(std::unique_ptr<detail::Bvh>& bvh, std::vector<detail::Box> boxes) const
{
    if (!bvh || bvh->size() != boxes.size()) bvh = std::make_unique<detail::Bvh>(std::move(boxes));
    else bvh->refit(std::move(boxes));
    return *bvh;
}

bool SelfContact::apart_at_rest(const ProximityPair& p, double d_hat) const
{
    // Primitives closer than the contact distance in the rest shape (neighbours
    // in a mesh finer than the fabric is thick) are not a contact: the barrier
    // would pre-stress the flat cloth.
    if (m_rest.rows() == 0) return true;
    return pair_squared_distance(p.kind, gather(m_rest, p.v)) >= d_hat * d_hat;
}

double SelfContact::drift(const Positions& X, double d_hat, const std::vector<char>& pinned) const
{
    const List& l = m_list;
    if (!l.valid || l.d_hat != d_hat || l.x0.rows() != X.rows() || l.pinned != pinned) return std::numeric_limits<double>::infinity();
    return std::sqrt((X - l.x0).rowwise().squaredNorm().maxCoeff());
}

void SelfContact::rebuild(const Positions& X, double d_hat, const std::vector<char>& pinned) const
{
    ++searches;
    List& l = m_list;
    l.x0 = X;
    l.d_hat = d_hat;
    l.skin = skin_of(d_hat);
    l.pinned = pinned;
    l.candidates.clear();
    l.valid = true;
    const double reach = d_hat + l.skin, reach2 = reach * reach;
    std::vector<detail::Box> vbox(static_cast<std::size_t>(X.rows()));
    for (Eigen::Index i = 0; i < X.rows(); ++i) vbox[static_cast<std::size_t>(i)].add(Vec3(X.row(i).transpose()));
    search(vbox, reach, [&](const ProximityPair& p) {
        if (!all_pinned(pinned, p.v) && pair_squared_distance(p.kind, gather(X, p.v)) < reach2 && apart_at_rest(p, d_hat))
            l.candidates.push_back(p);
    });
    std::sort(l.candidates.begin(), l.candidates.end(), [](const ProximityPair& a, const ProximityPair& b) {
        return std::tie(a.kind, a.v) < std::tie(b.kind, b.v);
    });
}

const std::vector<ProximityPair>& SelfContact::pairs(const Positions& X, double d_hat, const std::vector<char>& pinned) const
{
    Cache& c = m_cache;
    if (!(d_hat > 0)) {
        c.valid = false;
        c.pairs.clear();
        return c.pairs;
    }
    if (c.valid && m_list.valid && m_list.d_hat == d_hat && m_list.pinned == pinned && c.x.rows() == X.rows() &&
        std::memcmp(c.x.data(), X.data(), sizeof(double) * static_cast<std::size_t>(X.size())) == 0)
        return c.pairs;
    if (!(2 * drift(X, d_hat, pinned) < m_list.skin)) rebuild(X, d_hat, pinned);
    c.x = X;
    c.valid = true;
    c.pairs.clear();
    const double s_hat = d_hat * d_hat;
    for (const auto& p : m_list.candidates)
        if (pair_squared_distance(p.kind, gather(X, p.v)) < s_hat) c.pairs.push_back(p);
    return c.pairs;
}

double SelfContact::step_bound(const Positions& X, const Positions& D, double d_hat, const std::vector<char>& pinned,
                               double keep) const
{
    double alpha = 1;
    // The distance of a pair falls at most as fast as the largest relative
    // displacement of a vertex of one primitive against one of the other (the
    // closest points are convex combinations of the vertices).
    auto limit = [&](ProximityPair::Kind kind, const std::array<int, 4>& v) {
        const int first_b = kind == ProximityPair::PointTriangle ? 1 : 2;
        double m = 0;
        for (int a = 0; a < first_b; ++a)
            for (int b = first_b; b < 4; ++b) m = std::max(m, (D.row(v[static_cast<std::size_t>(a)]) - D.row(v[static_cast<std::size_t>(b)])).norm());
        if (!(m > 0)) return;
        if (!apart_at_rest({kind, v}, d_hat)) return; // not a contact (SelfContact::apart_at_rest)
        const double d0 = std::sqrt(pair_squared_distance(kind, gather(X, v)));
        if (!(d0 > 0)) return; // touching already: nothing left to keep
        const double floor = keep * d0;
        if (d0 - floor >= alpha * m) return; // cannot come that close within the step
        // Conservative advancement (the additive CCD of Li et al. 2021): from t,
        // the pair cannot lose more than m (t' - t) of its distance, so it may
        // advance by (d(t) - floor) / m; measuring d at the new t and repeating
        // approaches the first time it comes `floor` close (or the step's end).
        double t = 0, d = d0;
        for (int it = 0; it < 64; ++it) {
            const double dt = (d - floor) / m;
            if (!(dt > 1e-3 * (t + dt))) break; // converged on the approach
            t += dt;
            if (t >= alpha) return;
            const Positions& P = X;
            std::array<Vec3, 4> y;
            for (std::size_t k = 0; k < 4; ++k) y[k] = (P.row(v[k]) + t * D.row(v[k])).transpose();
            d = std::sqrt(pair_squared_distance(kind, y));
        }
        alpha = std::min(alpha, t);
    };
    // A pair off the candidate list was d_hat + skin apart at x0; it cannot
    // come within d_hat along the step while 2 (drift + |D|max) < skin.
    const double step = std::sqrt(D.rowwise().squaredNorm().maxCoeff());
    if (d_hat > 0 && 2 * (drift(X, d_hat, pinned) + step) < m_list.skin) {
        for (const auto& p : m_list.candidates) limit(p.kind, p.v);
        return alpha;
    }
    ++searches;
    std::vector<detail::Box> vbox(static_cast<std::size_t>(X.rows()));
    for (Eigen::Index i = 0; i < X.rows(); ++i) {
        vbox[static_cast<std::size_t>(i)].add(Vec3(X.row(i).transpose()));
        vbox[static_cast<std::size_t>(i)].add(Vec3((X.row(i) + D.row(i)).transpose()));
    }
    // Boxes padded by d_hat: pairs that end the step closer than d_hat are
    // bounded too (keeping 10 % of their distance), not only those that would touch.
    search(vbox, std::max(d_hat, 0.0), [&](const ProximityPair& p) { limit(p.kind, p.v); });
    return alpha;
}

} // namespace drape::cloth
