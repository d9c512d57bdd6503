#pragma once
// A cloth in a scene: mesh, model constants, colliders and the state (x, v).
// Forces, energies and their derivatives live here; integrators and the static
// solver (solver.hpp) drive it.
#include "engine/cloth/colliders.hpp"
#include "engine/cloth/mesh.hpp"
#include "engine/cloth/model.hpp"
#include "engine/cloth/profile.hpp"
#include "engine/cloth/self_contact.hpp"

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <array>
#include <memory>
#include <vector>

namespace drape::cloth {

struct ContactCache; // system.cpp

/// Holds the contact cache of one ClothSystem; a copy starts empty (a copied
/// system may get other colliders).
class ContactCacheHolder {
public:
    ContactCacheHolder();
    ~ContactCacheHolder();
    ContactCacheHolder(const ContactCacheHolder&);
    ContactCacheHolder& operator=(const ContactCacheHolder&);
    ContactCache& get() const { return *m_p; }

private:
    std::unique_ptr<ContactCache> m_p;
};

/// Coulomb friction against colliders for the static solver, lagged as in IPC
/// (Li et al. 2020, section 5): each vertex in contact has an anchor (where it
/// came into contact), the normal force lambda and normal n of the last lag
/// point (the static solver updates them every Newton iteration), and the
/// friction potential mu lambda f0(|P (x - anchor)|), P = I - n n^T, with
/// f0(y) = y beyond `eps` and -y^3/(3 eps^2) + y^2/eps + eps/3 below it: a
/// contact moved less than eps from its anchor sticks (a stiff tangential
/// spring), one moved farther slides against a force of mu lambda. At rest
/// every contact then carries a tangential force of at most mu lambda, the
/// Coulomb condition, reached along the solver's path from where the contacts
/// began (friction makes the rest state depend on the path).
struct StaticFriction {
    double eps = 1e-5;         ///< [m] sticking displacement (f0's smoothing)
    std::vector<char> active;  ///< per vertex: in contact at the lag point
    Positions anchor;          ///< [m]
    Eigen::VectorXd lambda;    ///< [N] normal force at the lag point
    Positions normal;          ///< unit collider normals at the lag point
    int contacts = 0;          ///< active vertices
};

/// Not safe for concurrent use from several threads, not even through const
/// methods: forces, energy and Hessian share a cache of the contacts found at
/// the last positions they were asked about (a Newton iteration asks for all
/// three at the same positions; the collider queries are its costliest part on
/// a body mesh).
class ClothSystem {
public:
    ClothSystem(ClothMesh mesh, ClothModel model);

    const ClothMesh& mesh() const { return m_mesh; }
    const ClothModel& model() const { return m_model; }
    ClothModel& model() { return m_model; }
    int vertex_count() const { return m_mesh.vertex_count(); }

    Positions x;      ///< current positions [m]
    Positions v;      ///< current velocities [m/s]
    double time = 0;  ///< [s]

    void add_collider(std::shared_ptr<const Collider> c) { m_colliders.push_back(std::move(c)); }
    const std::vector<std::shared_ptr<const Collider>>& colliders() const { return m_colliders; }
    void clear_colliders() { m_colliders.clear(); }

    /// Pinned vertices keep their position and get zero velocity.
    void set_pinned(int vertex, bool pinned);
    bool pinned(int vertex) const { return m_model.pinned[static_cast<std::size_t>(vertex)] != 0; }
    /// Per-vertex mass override [kg] (> 0). Contact stiffness follows the mass.
    void set_mass(int vertex, double mass);

    /// Potential energy: springs, membrane fibres, bending, gravity, contact, self-contact [J].
    double potential_energy(const Positions& X) const;
    double kinetic_energy(const Positions& V) const;

    /// Conservative force -dE/dx at X [N] (pinned rows included; callers mask them).
    void conservative_forces(const Positions& X, Positions& f) const;
    /// Total force for dynamics: conservative + dashpots + air damping + friction.
    /// Counts one force evaluation.
    void total_forces(const Positions& X, const Positions& V, Positions& f) const;

    /// Accumulates the damping forces (dashpots and air) at (X, V) into f.
    void add_damping_forces(const Positions& X, const Positions& V, Positions& f) const;

    mutable long force_evaluations = 0;
    /// When set, forces, energies, contact queries and Hessian assembly add their
    /// wall time here (see profile.hpp). Not owned.
    mutable SolveProfile* profile = nullptr;

    /// Gravity force per vertex [N] (zero on pinned vertices).
    Positions gravity_forces() const;
    /// Adds Coulomb friction of the contacts at X for velocity V (regularised
    /// below `v_eps` [m/s] so the force is continuous at rest).
    void add_friction_forces(const Positions& X, const Positions& V, Positions& f, double v_eps = 1e-4) const;

    /// Unique edges of the mesh's faces (a < b): where edge contact is checked.
    const std::vector<std::array<int, 2>>& edges() const { return m_edges; }
    /// Indices into edges() of the edges whose deepest point in a curved
    /// collider is inside the edge and in contact (ModelOptions::edge_contact).
    std::vector<int> edges_in_contact(const Positions& X) const;
    /// Free vertices in contact with any collider at X (a vertex in two counts once per collider).
    int vertex_contact_count(const Positions& X) const;

    /// When set (the static solver does, for ClothModel::friction > 0), the
    /// friction potential of `static_friction` is part of the potential energy,
    /// the conservative forces and the Hessian. Not owned.
    StaticFriction* static_friction = nullptr;
    /// Lag point of the static friction at X: vertices that came into contact
    /// are anchored where they are, vertices that left lose their anchor, and
    /// every contact's normal force and normal are taken at X.
    void update_static_friction(StaticFriction& sf, const Positions& X) const;
    /// Friction potential of vertex i at X with its gradient and Hessian (when
    /// asked); 0 when the vertex has no anchor.
    double static_friction_term(int i, const Positions& X, Eigen::Vector3d* grad = nullptr, Eigen::Matrix3d* hess = nullptr) const;

    /// Internal (system.cpp): the contacts found at the last positions asked about.
    ContactCache& contact_cache() const { return m_contact_cache.get(); }

    /// Self-contact on (ClothModel::self_contact_distance > 0).
    bool self_contact_on() const { return m_model.self_contact_distance > 0; }
    /// The self-contact pairs closer than the contact distance at X (empty when off).
    const std::vector<ProximityPair>& self_contact_pairs(const Positions& X) const;
    /// Energy, gradient and Hessian (when asked) of one self-contact pair at X.
    double self_contact_pair_energy(const ProximityPair& p, const Positions& X, Vec12* grad = nullptr, Mat12* hess = nullptr) const;
    /// Largest step fraction in (0, 1] along D from X that lets no two parts of
    /// the cloth pass through each other (1 when self-contact is off).
    double self_contact_step_bound(const Positions& X, const Positions& D) const;
    const SelfContact& self_contact() const { return m_self; }

private:
    friend class HessianAssembler;
    ClothMesh m_mesh;
    ClothModel m_model;
    std::vector<std::shared_ptr<const Collider>> m_colliders;
    std::vector<std::array<int, 2>> m_edges;
    ContactCacheHolder m_contact_cache;
    SelfContact m_self;
};

/// Sparse symmetric Hessian of the potential energy with a fixed sparsity
/// pattern (springs, stencils and per-vertex blocks), assembled in place: the
/// pattern and the value slot of every element block are computed once, so an
/// iteration only writes numbers (no triplet rebuild). Only the upper triangle
/// is stored (the form CHOLMOD takes). Spring blocks can be projected to
/// positive semi-definite (a compressed spring drops its negative transverse
/// term); contact uses the Gauss-Newton n n^T term.
class HessianAssembler {
public:
    explicit HessianAssembler(const ClothSystem& s);
    /// Which terms of the Hessian are projected to positive semidefinite.
    enum class Projection {
        None,     ///< the exact Hessian
        All,      ///< springs and contact (the Gauss-Newton n n^T term only)
    };
    /// H = d2E/dx2 (with `projection`) + diag(extra_diag_i I) + damping_scale * D(X),
    /// with D the dashpot and air damping matrix. Pinned rows and columns become identity.
    void assemble(const Positions& X, const Eigen::VectorXd& extra_diag, double damping_scale, Projection projection);
    void assemble(const Positions& X, const Eigen::VectorXd& extra_diag, double damping_scale, bool project = true)
    {
        assemble(X, extra_diag, damping_scale, project ? Projection::All : Projection::None);
    }
    const Eigen::SparseMatrix<double>& matrix() const { return m_H; }
    /// Counts changes of the sparsity pattern: self-contact pairs between vertices
    /// the pattern did not couple yet add their blocks (the pattern only grows).
    /// A factorisation analysed for an older revision must be analysed again.
    int revision() const { return m_revision; }

private:
    struct Block {
        int col[3]; ///< value index of entry (0, b) of the block in column b; entry (a, b) is col[b] + a
    };
    Block block(int i, int j) const; ///< i <= j
    bool has_block(int i, int j) const; ///< i <= j
    void build_pattern();
    /// Adds self-contact pairs' vertex couplings the pattern lacks (a new revision).
    void grow_pattern(const std::vector<ProximityPair>& self_pairs);
    /// Adds the symmetric 3x3 K to a diagonal block (its upper triangle only) or
    /// to an off-diagonal block.
    void add_diag(const Block& bl, const Eigen::Matrix3d& K);
    void add_off(const Block& bl, const Eigen::Matrix3d& K);
    // The terms of assemble, in its order.
    void add_springs(const Positions& X, double damping_scale, bool project_springs);
    void add_fibers(const Positions& X, double damping_scale, bool project_springs);
    void add_bends(const Positions& X, double damping_scale);
    void add_diagonal(const Eigen::VectorXd& extra_diag, double damping_scale);
    void add_anchors();
    void add_contacts(const Positions& X, bool project_contacts);
    void add_self_contacts(const std::vector<ProximityPair>& self_pairs, const Positions& X, bool project_contacts);
    /// Pinned vertices: identity rows and columns.
    void pin_rows();
    int m_revision = 0;
    std::vector<std::pair<int, int>> m_extra; ///< coupled by self-contact (i < j)
    const ClothSystem& m_s;
    Eigen::SparseMatrix<double> m_H; // 3n x 3n, upper triangle
    std::vector<std::vector<int>> m_nbr; // per column vertex j: sorted row vertices i <= j
    std::vector<Block> m_spring_blocks;  // per spring: off-diagonal block (min, max)
    std::vector<Block> m_diag_blocks;    // per vertex
    std::vector<Block> m_bend_blocks;        // every stencil's pairs (p<q) in order 01,02,..,12,..; n(n-1)/2 each
    std::vector<std::size_t> m_bend_offset;  // per stencil: its first pair in m_bend_blocks
    std::vector<Block> m_edge_blocks;    // per mesh edge (ClothSystem::edges): off-diagonal block
    std::vector<Block> m_fiber_blocks;   // per membrane fibre: its three off-diagonal blocks (pairs 01, 02, 12)
    std::vector<Block> m_arc_blocks;     // every arc spring's node pairs (p < q in arc_nodes' order)
    std::vector<std::size_t> m_arc_offset; // per spring: its first pair in m_arc_blocks (arc springs only)
};

} // namespace drape::cloth
