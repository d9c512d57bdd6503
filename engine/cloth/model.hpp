#pragma once
// Per-element constants of the mass-spring model for one mesh, made from
// continuum parameters (the one documented mapping) or from explicit grid
// springs (the seed paper's model, whose file format lives in engine/fabric).
#include "engine/cloth/mesh.hpp"
#include "engine/cloth/params.hpp"

#include <array>
#include <optional>
#include <cmath>
#include <string>
#include <vector>

namespace drape::cloth {

enum class SpringKind : unsigned char { StretchU, StretchV, Shear, FlexionU, FlexionV, Edge };

/// The spring law of an extension x (see Spring): energy [J] and its first and
/// second derivative in x, for stiffness k and compressive force limit fc.
inline void spring_law(double x, double k, double fc, double& e, double& de, double& d2e)
{
    if (fc == 0 && x < 0) {
        e = de = d2e = 0;
        return;
    }
    const double x1 = -0.5 * fc / k;
    if (fc > 0 && x < x1) {
        const double h = 0.5 * fc, q = std::exp((x - x1) * k / h);
        e = 0.5 * k * x1 * x1 - fc * (x - x1) + h * h / k * (q - 1);
        de = -fc + h * q;
        d2e = k * q;
        return;
    }
    e = 0.5 * k * x * x;
    de = k * x;
    d2e = k;
}

/// Stiffness of a slack element in its slack, as a fraction of its tensile
/// stiffness (Param::CompressionSlack).
inline constexpr double kSlackStiffnessFraction = 0.01;

/// spring_law with slack in compression (Param::CompressionSlack): the element
/// shortens by its first `slack` [m] at kSlackStiffnessFraction of k, the yarns'
/// crimp taking it up, and then resists as spring_law does from that point on:
///   E(x) = eps k x^2 / 2 + (1 - eps) E_fc(min(0, x + slack))   for x < 0,
/// tension unchanged. Force continuous; the stiffness steps from k to eps k at
/// x = 0 and back at x = -slack (as a no-compression element's does at 0).
/// slack = 0: spring_law.
inline void slack_spring_law(double x, double k, double fc, double slack, double& e, double& de, double& d2e)
{
    if (!(slack > 0) || x >= 0 || fc == 0) {
        spring_law(x, k, fc, e, de, d2e);
        return;
    }
    constexpr double eps = kSlackStiffnessFraction;
    e = 0.5 * eps * k * x * x;
    de = eps * k * x;
    d2e = eps * k;
    if (x + slack < 0) {
        double e2, de2, d2e2;
        spring_law(x + slack, k, fc, e2, de2, d2e2);
        e += (1 - eps) * e2;
        de += (1 - eps) * de2;
        d2e += (1 - eps) * d2e2;
    }
}

/// Spring with a dashpot along it (Provot 1995). Energy 1/2 k x^2 in the extension
/// x = |xi - xj| - rest, except in compression towards the strip's buckling load:
/// with fc > 0 the compressive force approaches fc and never exceeds it, the
/// post-buckling response of Choi and Ko 2002 ("Stable but responsive cloth"): a
/// strip shorter than its rest length by more than about fc / k has buckled at a
/// scale below the mesh. fc is the Euler stress of the fabric, pi^2 B / l^2 per
/// unit width (Param::BucklingLength l), times the width of the strip the spring
/// stands for: a force per unit width that does not depend on the mesh. The force is linear up to half the buckling load and
/// then saturates exponentially,
///   f(x) = -fc + fc/2 exp(2 k (x - x1) / fc)   for x < x1 = -fc / (2 k),
/// so force and stiffness are continuous (the energy is C2: Newton's method keeps
/// its quadratic rate where springs sit at the transition, which a hard cap, C1
/// only, loses) and the stiffness stays positive. fc = 0: no compressive force.
struct Spring {
    int i, j;
    double rest; ///< [m]
    double k;    ///< [N/m]
    double d;    ///< [N*s/m]
    SpringKind kind;
    double fc = -1; ///< [N] compressive force limit; < 0: linear in compression too
    double slack = 0; ///< [m] shortening taken up almost freely (slack_spring_law); 0: none
    int arc = -1;   ///< index into ClothModel::arcs: the spring measures its material line's arc, not its chord; < 0: the chord
    /// Energy [J], its first and second derivative in the length [N], [N/m].
    void law(double length, double& e, double& de, double& d2e) const { slack_spring_law(length - rest, k, fc, slack, e, de, d2e); }
};

/// One fibre family of one triangle of a general mesh: the triangle's membrane
/// (make_model) is the continuum of the grid's spring net - warp, weft and the two
/// diagonals - so that a preset means the same on any mesh. The fibre's current
/// vector is d = sum_a w_a x_a over the triangle's vertices (the deformation
/// gradient applied to the fibre's material direction, times `rest`), its length
/// |d| is `rest` when unstretched, and the energy is Spring's law of |d| - rest
/// (linear, or with the compression limit fc: the sub-mesh buckling of the
/// strip). Weights sum to zero: rigid motions cost nothing.
struct MembraneFiber {
    std::array<int, 3> v{-1, -1, -1};
    std::array<double, 3> w{0, 0, 0}; ///< [1]
    double rest; ///< [m]
    double k;    ///< [N/m]
    double d;    ///< [N*s/m]
    double fc = -1; ///< [N]
    double slack = 0; ///< [m] (slack_spring_law)
    /// The fibre's current vector at positions X.
    template <class P>
    Eigen::Vector3d vec(const P& X) const
    {
        return w[0] * X.row(v[0]).transpose() + w[1] * X.row(v[1]).transpose() + w[2] * X.row(v[2]).transpose();
    }
    void law(double length, double& e, double& de, double& d2e) const { slack_spring_law(length - rest, k, fc, slack, e, de, d2e); }
};

/// Quadratic bending stencil (after Bergou, Wardetzky, Harmon, Zorin, Grinspun
/// 2006, "A quadratic bending model for inextensible surfaces"): energy
/// 1/2 k |sum_i w_i x_i|^2 over 3 nodes along a grid line, the 4 of a grid
/// cell, or the 6-9 nodes around a triangle of a general mesh (one stencil per
/// second derivative x_uu, x_uv, x_vv). The weights sum to zero and annihilate every affine map of the
/// flat rest shape, so the energy is zero when flat, rotation invariant, its
/// Hessian is constant, and it resists bending linearly from the flat state.
/// They are scaled so that sum_i w_i x_i is the curvature vector [1/m] for a
/// cylindrical bend across the stencil.
struct BendStencil {
    static constexpr int kMax = 9;
    int n = 3;        ///< 3 (grid line), 4 (grid cell), up to 9 (a grid's 3x3 block at the hem; a triangle and its neighbours)
    int v[kMax] = {-1, -1, -1, -1, -1, -1, -1, -1, -1};
    double w[kMax] = {}; ///< [1/m^2]
    double k; ///< [N*m^3]: energy in J with weights in 1/m^2 and positions in m
    double d; ///< [N*m^3*s] damping of the same stencil
    /// [m^2] The stencil's own fourth-order correction (ModelOptions::bending_correction).
    /// A second difference s = sum w_a x_a over spacing h through nodes on a bend of
    /// curvature kappa reads kappa (1 - h^2 kappa^2 / 12) along the line, so its energy is
    /// short by h^2 kappa^2 / 6: at a fold crest one cell in radius (grid 41 on 300 mm) by
    /// 15 %. The material's law (linear, ClothModel::bend_stiffening, bend_softening) is
    /// taken of the corrected squared curvature |s|^2 (1 + quartic |s|^2 / 2) instead of
    /// |s|^2; the linear law's energy is then k (|s|^2 / 2 + quartic |s|^4 / 4).
    /// quartic = h^2 / 3 restores it to O(h^4) along a line; the mixed difference over a
    /// cell (hu, hv) is short by hu hv kappa^2 / 12 and needs 2 hu hv / 3, exact for a fold
    /// at 45 degrees to the grid, where the twist stencils carry the most energy. 0 = none.
    double quartic = 0;
};

/// The arc of a spring's material line (ModelOptions::arc_membrane). A spring
/// between two nodes of a bent sheet is the chord of the material line between
/// them, shorter than the line by h^3 kappa^2 / 24 (h its length, kappa the line's
/// curvature): a fold crest one cell in radius reads 4 % compression where the
/// cloth has none, and past the compression limit's onset that costs work the
/// continuum does not do, more on coarser meshes (the membrane locking measured in
/// docs/decisions/0019-drapemeter-mesh.md). With an arc the spring's length
/// is the line's: |x_i - x_j| + c_0 |s_0|^2 + c_1 |s_1|^2, s_e = sum_a w_a x_a the
/// second derivative of the positions along the spring's direction at its end e
/// (the grid's central differences; least squares over the 3x3 block at the hem),
/// c_e = rest^3 / 48 each (rest^3 / 24 on one end when the other has none). The
/// weights annihilate affine maps: a flat sheet's springs are their chords.
/// The element's nodes are listed once (v[0], v[1] the spring's ends, then the other
/// nodes of either end's weights: each end's weights include the end itself), so the
/// forces and the Hessian's blocks go over one list made with the model.
struct SpringArc {
    static constexpr int kMax = 2 + 2 * (BendStencil::kMax - 1);
    int n = 0;                   ///< nodes in v
    int v[kMax] = {};
    double w[2][kMax] = {};      ///< [1/m^2] end e's curvature weight at node v[k] (0: not in its stencil)
    double c[2] = {0, 0};        ///< [m^3]
    /// The position of node x in v, appended if new.
    int slot(int x);
    /// The spring's arc length, and the curvature vectors s_0, s_1, at positions X.
    template <class P>
    double length(const P& X, Eigen::Vector3d (&s)[2]) const
    {
        double L = (X.row(v[0]) - X.row(v[1])).norm();
        for (int e = 0; e < 2; ++e) {
            s[e].setZero();
            for (int k = 0; k < n; ++k)
                if (w[e][k] != 0) s[e] += w[e][k] * X.row(v[k]).transpose();
            L += c[e] * s[e].squaredNorm();
        }
        return L;
    }
};

enum class BendingModel { Quadratic, Flexion, Both };

struct ModelOptions {
    BendingModel bending = BendingModel::Quadratic;
    /// Contact penalty: a vertex resting on a collider under its own weight sinks
    /// by this much [m]; sets the penalty stiffness m g / depth per vertex.
    double contact_depth = 2e-6;
    /// Contact of mesh edges with curved colliders (pedestal rim, spheres), not only
    /// of vertices: without it a coarse element between a vertex on the disc and one
    /// hanging below it cuts the corner of the pedestal (3.9 mm deep at grid 25), and
    /// the laser slices next to the disc come out too narrow (docs/decisions/0001-edge-contact.md).
    bool edge_contact = true;
    /// Self-contact (engine/cloth/self_contact.hpp): a barrier pushes apart every
    /// point and triangle and every two edges of the cloth that come closer than
    /// its thickness (kMinSelfContactDistance at the least; a layer resting on
    /// another sits about 0.8 of it above), and no step of the static solver or
    /// the implicit integrator lets them pass through each other. Off by default: a drapemeter's folds stay open, and
    /// the proximity search costs time; the garment scenes switch it on
    /// (docs/decisions/0007-self-contact-garments-only.md). Explicit integrators ignore it (a barrier needs the step filter).
    bool self_collision = false;
    /// The grid's bending stencils carry their fourth-order correction
    /// (BendStencil::quartic): a fold crest one cell in radius stores the continuum's
    /// bending energy to about 4 % (7 % at 45 degrees) instead of 15 % short. Off in the
    /// engine (the unit tests' synthetic records and the blind suite are made without
    /// it); on in `drape fit`'s defaults and the starter presets, where with grid 41
    /// as the coarsest level the starters converge within 1 point over grids 41-81 and
    /// the fits' held-out error falls (docs/decisions/0011-bending-correction.md).
    /// A general triangle mesh's stencils need none (exact for quadratic surfaces; a grid garment, the tablecloth, has it).
    /// Presets carry it as model.bending_correction.
    bool bending_correction = false;
    /// The grid's springs measure the arc of their material line, not its chord
    /// (SpringArc): a fold's crest no longer reads as compression of the springs
    /// across it. Grid meshes only (a general mesh's membrane fibres are per triangle).
    /// Presets carry it as model.arc_membrane.
    bool arc_membrane = false;
};

/// A horizontal tether of a material point to a place: energy 1/2 k |P (x - target)|^2
/// with P the projection on the horizontal plane and x = sum_a w_a x_{v_a} the point
/// interpolated from up to four vertices (a vertex: one weight 1; the middle of a
/// grid cell: four weights 1/4). It stands for the static friction that holds a
/// specimen's centre on the drapemeter disc: without it a sheet on a frictionless
/// disc is in unstable equilibrium against sliding sideways (the longer overhang
/// pulls harder). Tethering the exact material centre keeps the set-up symmetric
/// about the pedestal axis: a tether on the vertex nearest the centre (off the axis
/// on even grids) leaves an almost free rotation that the static solver drifts along.
struct HorizontalAnchor {
    int n = 1;                          ///< vertices used
    std::array<int, 4> v{-1, -1, -1, -1};
    std::array<double, 4> w{1, 0, 0, 0}; ///< interpolation weights, summing to 1
    Eigen::Vector3d target;             ///< [m]
    double k;                           ///< [N/m]
    static HorizontalAnchor at_vertex(int vertex, const Eigen::Vector3d& target, double k)
    {
        HorizontalAnchor a;
        a.v[0] = vertex;
        a.target = target;
        a.k = k;
        return a;
    }
    /// The anchored point at positions X.
    template <class P>
    Eigen::Vector3d point(const P& X) const
    {
        Eigen::Vector3d x = Eigen::Vector3d::Zero();
        for (int i = 0; i < n; ++i) x += w[static_cast<std::size_t>(i)] * X.row(v[static_cast<std::size_t>(i)]).transpose();
        return x;
    }
};

struct ClothModel {
    std::vector<Spring> springs;
    std::vector<MembraneFiber> fibers; ///< the membrane of a general triangle mesh (a grid's is its springs)
    std::vector<SpringArc> arcs;       ///< Spring::arc's (ModelOptions::arc_membrane)
    std::vector<BendStencil> bends;
    Eigen::VectorXd mass;             ///< [kg] per vertex
    std::vector<char> pinned;         ///< per vertex
    std::vector<HorizontalAnchor> anchors;
    Eigen::Vector3d gravity{0, 0, -9.81}; ///< [m/s^2]
    double air_damping = 0;           ///< [1/s]
    double contact_offset = 0;        ///< [m] half the thickness
    double friction = 0;              ///< Coulomb coefficient
    /// Stiffening of every bending stencil [m^2] (r^2 of Param::BendStiffeningRadius):
    /// a stencil with second difference d = sum w_a x_a has energy
    /// k (|d|^2 / 2 + bend_stiffening |d|^4 / 4), i.e. per unit area
    /// B kappa^2 / 2 + B r^2 kappa^4 / 4 and a moment B kappa (1 + r^2 kappa^2). 0 = linear.
    /// With BendStencil::quartic, |d|^2 is the corrected squared curvature (see there).
    double bend_stiffening = 0;
    /// Softening of every bending stencil [m^2] (rho^2 of Param::BendSofteningRadius):
    /// energy k (sqrt(1 + rho^2 |d|^2) - 1) / rho^2 instead of k |d|^2 / 2, a moment
    /// B kappa / sqrt(1 + rho^2 kappa^2) that saturates at B / rho. 0 = linear. With
    /// BendStencil::quartic, of the corrected squared curvature (see there).
    double bend_softening = 0;
    /// Peaking bending of every stencil [m^2] (R^2 of Param::BendPeakRadius): energy
    /// k ln(1 + R^2 |d|^2) / (2 R^2) instead of k |d|^2 / 2, a moment B kappa / (1 + R^2
    /// kappa^2) that peaks at B / (2 R) where kappa = 1 / R and falls beyond (a stencil
    /// bent past it is not convex: the cloth hinges). 0 = linear; not with bend_softening.
    double bend_peak = 0;
    bool edge_contact = true;         ///< see ModelOptions::edge_contact
    /// Self-contact distance d_hat [m] (ModelOptions::self_collision): 0 = off.
    double self_contact_distance = 0;
    Eigen::VectorXd contact_stiffness;///< [N/m] per vertex
    std::string description;

    int vertex_count() const { return static_cast<int>(mass.size()); }
    double total_mass() const { return mass.sum(); }
    /// The length spring `sp` measures at positions X: its arc (Spring::arc) or its chord.
    template <class P>
    double spring_length(const Spring& sp, const P& X) const
    {
        if (sp.arc < 0) return (X.row(sp.i) - X.row(sp.j)).norm();
        Eigen::Vector3d s[2];
        return arcs[static_cast<std::size_t>(sp.arc)].length(X, s);
    }
};

/// The mapping from continuum parameters to element constants (SI throughout).
/// On a grid with spacings hu, hv:
///   stretch u spring  k = (E_u - G hu^2/hv^2) hv/hu  (the shear diagonals already carry G hu^2/hv^2 of E_u;
///                     floored at E_u hv/hu / 2 so a large G never makes it soft)
///   shear diagonals   k = G (hu^2 + hv^2) / (2 hu hv)   (energy 1/2 G gamma^2 per unit area)
///   bending u stencil weights (1, -2, 1)/hu^2, k = B_u hu hv  (energy 1/2 B_u kappa^2 per unit area)
///   twist stencil per cell, weights (1, -1, -1, 1)/(hu hv), k = 2 sqrt(B_u B_v) hu hv, so a fold
///                     at any angle to the grid costs what it costs along a grid line
///   dampers use the same formulas with the damping coefficients.
///   mass              m_i = rho_A * (lumped vertex area)
/// Hem nodes snapped onto the cut circle keep springs with their true rest
/// lengths; bending stencils through them use the divided-difference weights
/// of their true spacings along the grid line.
/// General triangle meshes get the continuum of that spring net per triangle
/// (MembraneFiber: warp, weft and both diagonals, the grid's moduli and
/// compression limits; exact for affine deformations on any triangulation) and
/// per-triangle curvature stencils for the orthotropic plate (x_uu, x_uv, x_vv of
/// the quadratic through the triangle and its neighbours).
ClothModel make_model(const ClothMesh& mesh, const FabricParams& p, const ModelOptions& opt = {});

/// A mass-spring grid given by its element constants instead of continuum
/// values (SI): the seed paper's model is one (its 19 constants in paper
/// units are engine/fabric/seed_format.hpp's business). The constants belong
/// to one grid: a `width` x `height` sheet of `cells_u` x `cells_v` square
/// patches, simulated on that grid only.
struct GridSprings {
    double width = 0.30, height = 0.30;   ///< [m] the sheet the grid spans
    int cells_u = 30, cells_v = 30;       ///< patches along u (warp) and v (weft); nodes = cells + 1
    double particle_mass = 2e-5;          ///< [kg] every node
    double k_u = 150, d_u = 7;            ///< structural springs along u [N/m], [N*s/m]
    double k_v = 150, d_v = 7;            ///< along v
    double k_shear = 40, d_shear = 6;     ///< both diagonals of every patch
    double k_flex_u = 24, d_flex_u = 8;   ///< skip-one (flexion) springs along u
    double k_flex_v = 24, d_flex_v = 8;   ///< along v
    /// ParameterError naming the field when a constant is non-finite or negative,
    /// a stiffness or the mass is not positive, or the grid is smaller than 4 cells.
    void validate(const std::string& where) const;
};

/// What a cloth is made of, as the scene builders take it: continuum
/// parameters, mapped onto any mesh by make_model, or - for the seed's
/// presets - explicit grid springs that only exist on their own grid. For
/// those, `params` holds their continuum equivalents (stretch, shear, mass;
/// bending at its default: flexion springs have no continuum counterpart),
/// which is what a garment made of that preset uses.
struct Material {
    FabricParams params;
    std::optional<GridSprings> grid_springs;
    Material() = default;
    Material(const FabricParams& p) : params(p) {} // NOLINT: a continuum fabric is a material
    Material(const FabricParams& p, const GridSprings& g) : params(p), grid_springs(g) {}
};

/// The grid-spring model on its own grid: structural, shear and flexion springs
/// with the given constants, every node of mass `particle_mass`. `mesh` must be
/// a grid mesh; `opt.bending` must not be Quadratic (these are spring constants).
ClothModel make_grid_spring_model(const ClothMesh& mesh, const GridSprings& g, const ModelOptions& opt = {});

} // namespace drape::cloth
