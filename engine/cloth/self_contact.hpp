#pragma once
// Self-contact of the cloth: a barrier on the distance between every point and
// triangle and every two edges of the mesh that share no vertex, so that the
// static solver and the implicit integrator never let the cloth pass through
// itself (Li et al., "Incremental Potential Contact", SIGGRAPH 2020; the
// barrier, the edge-edge mollifier and the step filter follow that paper).
//
//   E = sum over pairs closer than d_hat of  m * (k s_hat / 2) * beta(s / s_hat),
//   beta(u) = -(u - 1)^2 ln u,   s = d^2,  s_hat = d_hat^2,
//
// with k = (mean weight of the pair's vertices) / (kSelfContactSqueeze d_hat)
// [N/m] (ClothSystem::self_contact_pair_energy), d_hat the self-contact
// distance (the fabric's thickness: two layers' mid-surfaces one thickness
// apart), and m = 1 for point-triangle pairs and IPC's mollifier of
// |e_a x e_b|^2 for edge pairs (C1 as the edges turn parallel, where the
// edge-edge distance changes type). The distance's derivatives are those of the
// closest-point problem's envelope: exact wherever the closest points are
// unique (inside a face, edge or vertex region), which the finite-difference
// tests check region by region.
//
// The energy is infinite at touching, so a step that would let two primitives
// pass through each other must be cut before the line search sees it:
// SelfContact::step_bound is a conservative continuous collision check (the
// distance of a pair cannot fall faster than the largest relative
// displacement of its vertices), as IPC's step filter.
#include "engine/cloth/mesh.hpp"

#include <Eigen/Core>

#include <array>
#include <memory>
#include <vector>

namespace drape::cloth {

namespace detail {
class Bvh;
struct Box;
} // namespace detail

/// The smallest self-contact distance [m]: a fabric declared thinner (or of
/// thickness 0) keeps its layers this far apart, so the barrier stays
/// resolvable in double precision on metre-scale scenes.
inline constexpr double kMinSelfContactDistance = 1e-4;

/// The barrier's stiffness per pair is (mean vertex weight) / (squeeze d_hat):
/// a layer resting on another under its own weight sits about 0.8 d_hat above it.
inline constexpr double kSelfContactSqueeze = 0.25;

using Vec12 = Eigen::Matrix<double, 12, 1>;
using Mat12 = Eigen::Matrix<double, 12, 12>;

/// Two primitives of a mesh close to each other: a point and a triangle (v[0];
/// v[1], v[2], v[3]) or two edges (v[0]-v[1] and v[2]-v[3]). No vertex appears twice.
struct ProximityPair {
    enum Kind : unsigned char { PointTriangle, EdgeEdge };
    Kind kind = PointTriangle;
    std::array<int, 4> v{};
};

/// Squared distance [m^2] between the primitives at x (in ProximityPair::v's
/// order), with its gradient and Hessian in (x0, x1, x2, x3) when asked for.
double pair_squared_distance(ProximityPair::Kind kind, const std::array<Eigen::Vector3d, 4>& x, Vec12* grad = nullptr,
                             Mat12* hess = nullptr);

/// Barrier energy [J] of one pair at x: stiffness k [N/m], distance d_hat [m];
/// `eps_cross` [m^4] is the edge-edge mollifier's threshold on |e_a x e_b|^2
/// (ignored for point-triangle pairs). 0 at and beyond d_hat, +inf at touching.
/// Gradient and Hessian (exact) when asked for.
double pair_energy(ProximityPair::Kind kind, const std::array<Eigen::Vector3d, 4>& x, double k, double d_hat,
                   double eps_cross, Vec12* grad = nullptr, Mat12* hess = nullptr);

/// The self-contact of one mesh: its primitives, the pairs closer than the
/// contact distance at a set of positions (cached for the last positions asked
/// about), their energy, forces and the safe step. Not thread-safe (the cache).
class SelfContact {
public:
    SelfContact();
    SelfContact(const Triangles& F, const std::vector<std::array<int, 2>>& edges, const Positions& rest);
    ~SelfContact();
    SelfContact(const SelfContact& o);
    SelfContact& operator=(const SelfContact& o);

    /// Pairs closer than d_hat [m] at X, skipping pairs whose four vertices are
    /// all pinned. Sorted (kind, vertices): the same positions give the same list.
    const std::vector<ProximityPair>& pairs(const Positions& X, double d_hat, const std::vector<char>& pinned) const;
    /// The edge-edge mollifier's threshold of a pair (1e-3 |e_a|^2 |e_b|^2 at rest) [m^4].
    double eps_cross(const ProximityPair& p) const;
    /// Largest alpha in (0, 1] such that no pair of X + t D, 0 <= t <= alpha,
    /// comes closer than `keep` times its distance at X (pairs that touch at X
    /// are left out), for a contact distance d_hat. 1 when nothing can come near.
    double step_bound(const Positions& X, const Positions& D, double d_hat, const std::vector<char>& pinned,
                      double keep = 0.1) const;

    mutable long searches = 0; ///< full broad-phase searches (candidate lists built, step bounds without a list)

private:
    Triangles m_F;
    std::vector<std::array<int, 2>> m_edges;
    Positions m_rest; ///< rest positions (the mollifier's edge lengths)
    /// A Verlet list: the pairs closer than d_hat + skin at x0. While no vertex
    /// has moved skin / 2 from x0, every pair closer than d_hat is on it (a
    /// pair's distance changes at most by twice the largest displacement), so a
    /// query only measures the listed pairs; the broad phase runs again when
    /// the cloth has moved on.
    struct List {
        Positions x0;
        double d_hat = -1, skin = 0;
        std::vector<char> pinned;
        std::vector<ProximityPair> candidates;
        bool valid = false;
    };
    mutable List m_list;
    struct Cache {
        Positions x;
        std::vector<ProximityPair> pairs;
        bool valid = false;
    };
    mutable Cache m_cache;
    /// Largest displacement of a vertex from the list's positions [m] (infinite
    /// when the list is not for this contact distance, pinning or size).
    double drift(const Positions& X, double d_hat, const std::vector<char>& pinned) const;
    void rebuild(const Positions& X, double d_hat, const std::vector<char>& pinned) const;
    bool apart_at_rest(const ProximityPair& p, double d_hat) const;
    /// The hierarchies over triangles and edges: built on the first search,
    /// refitted to the boxes of every later one (copies start without them).
    mutable std::unique_ptr<detail::Bvh> m_tri_bvh, m_edge_bvh;
    const detail::Bvh& refit(std::unique_ptr<detail::Bvh>& bvh, std::vector<detail::Box> boxes) const;
    /// f(pair) for every point-triangle and edge-edge pair sharing no vertex whose
    /// boxes overlap: the vertices' boxes `vbox` (points or swept), triangles' and
    /// edges' boxes their vertices' boxes padded by `pad` and pad / 2.
    template <class F>
    void search(const std::vector<detail::Box>& vbox, double pad, F&& f) const;
};

} // namespace drape::cloth
