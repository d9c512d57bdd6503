#pragma once
// Garment scenes, free of any GUI: a circular skirt generated around a
// mannequin's waist and a round tablecloth on a round table, as cloth systems
// ready to drape with a fabric preset. The demo, the widget and `drape garment`
// use the same functions, so what a test checks is what the user sees.
//
// World frame: Drapekit's (z up, metres); the table stands on the floor z = 0.
#include "importers/body.hpp"

#include "engine/cloth/solver.hpp"
#include "engine/cloth/system.hpp"
#include "engine/fabric/preset.hpp"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace drape::importers {

/// A flat annulus (circular skirt pattern) in the plane z = `z` [m] around
/// `centre`: `rings` + 1 circles from `inner_radius` to `outer_radius` [m],
/// spaced geometrically so triangles keep their shape, `segments` vertices per
/// circle. Inner circle vertices are marked in `waistband`. Throws
/// ParameterError on radii <= 0, outer <= inner, segments < 8 or rings < 1.
struct Panel {
    cloth::Positions X;
    cloth::Triangles F;
    std::vector<int> waistband;
};
Panel make_annulus(const Eigen::Vector2d& centre, double z, double inner_radius, double outer_radius, int segments,
                   int rings);

/// Sizes of the generated skirt, relative to the measured waist.
struct SkirtOptions;

/// The start shape of a skirt pattern `p` pinned at its waistband (radius
/// `r_in` [m] around `centre`, height `z_band` [m]): each ring hangs on a
/// nearly vertical cone (3 degrees) that clears the body, its length gathered
/// into eight outward folds, so the drape starts outside the body with springs
/// near their rest length (a flat pattern would cut through arms held away
/// from the body) and the fabric chooses its own flare. The number of folds is
/// the start's: the static solver finds the rest state nearest to it.
cloth::Positions hang_skirt(const Mannequin& m, const Panel& p, const Eigen::Vector2d& centre, double z_band,
                            double r_in, const SkirtOptions& opt);

/// The part of the body a skirt touches: the triangles below `z_top` [m] and
/// within the hips' reach of the vertical axis through `axis` (the hips' widest
/// section + 5 cm), padded like Mannequin::contact. Arms and hands held away
/// from the body (an A-pose) are left out: a skirt dropped from the waist falls
/// where they are, as in a fitting room with the arms raised.
std::shared_ptr<const MeshCollider> lower_body_collider(const Mannequin& m, double z_top, const Eigen::Vector2d& axis);

/// Garment choice.
enum class Garment { Skirt, Tablecloth, Mesh };
Garment parse_garment(const std::string& name); ///< "skirt" (or "circle-skirt") | "tablecloth"; ParameterError otherwise
std::string to_string(Garment g);

/// A round table standing on the floor.
struct Table {
    double radius = 0.45;     ///< [m]
    double height = 0.75;     ///< [m] top above the floor
    double cloth_diameter = 1.5; ///< [m] round tablecloth
};

/// Sizes of the generated skirt, relative to the measured waist.
struct SkirtOptions {
    /// Flat: the pattern as cut, a flat annulus at the waistband, dropped (the
    /// fabric makes its own folds). Gathered: hung on a near-vertical cone
    /// gathered into eight folds (the start decides the folds; for comparison).
    enum class Start { Flat, Gathered } start = Start::Flat;
    double length = 0.50;       ///< [m] from waistband to hem, flat
    double ease = 0.012;        ///< [m] waistband radius beyond the waist's farthest point
    double lift = 0.02;         ///< [m] waistband above the waist
    int segments = 96;          ///< around
    int rings = 0;              ///< across; 0 = from segments so triangles are near equilateral
};

/// A cloth scene ready to drape, plus what the view needs to draw it.
struct Scene {
    Garment garment = Garment::Skirt;
    std::unique_ptr<cloth::ClothSystem> system;
    std::shared_ptr<const Mannequin> mannequin; ///< skirt only
    Table table;                                ///< tablecloth only
    Girth waist;                                ///< skirt and garment meshes: the body's waist (its centre is the axis)
    std::string fabric_name;
    std::string garment_name;                   ///< "circle skirt", "tablecloth" or the garment file
};

/// Skirt on the mannequin: annulus around the measured waist, waistband pinned,
/// colliders = body (MeshCollider) + floor. FabricParams are required; a seed
/// preset is converted with fabric::continuum_from_seed.
Scene make_skirt_scene(std::shared_ptr<const Mannequin> m, const fabric::FabricPreset& fabric,
                       const SkirtOptions& opt = {});
/// A garment mesh from a file (OBJ or anything assimp reads), on the mannequin.
/// The vertices that hold it are declared in the file: every vertex of a mesh,
/// object or group whose name starts with "pin" or "waist" (case-insensitive;
/// in OBJ: `g waist` before the waistband's faces) is pinned where it is. The
/// rest drapes from the shape the file gives it. Colliders: the body and the
/// floor. Throws FileError / ParameterError naming the file when it has no such
/// group, or nothing else to drape.
Scene make_garment_scene(std::shared_ptr<const Mannequin> m, const std::string& path, const fabric::FabricPreset& fabric,
                         const ImportOptions& opt = {});

/// Round tablecloth centred on a round table: colliders = table top (a
/// PedestalCollider: top radius, height) + floor; a small symmetry-breaking
/// lift as in the drapemeter so folds can form.
Scene make_tablecloth_scene(const fabric::FabricPreset& fabric, const Table& table = {}, int grid = 45,
                            std::uint64_t seed = 1);

/// How a skirt settles from its flat pattern before the static solve: implicit
/// Euler under gravity with a strong air damping, i.e. an overdamped
/// (quasi-static) fall. The cloth then follows the fall of its own energy, as a
/// skirt put on slowly does, and the folds are the ones its bending and shear
/// choose; inertia (a fast drop that swings and overshoots) would add folds of
/// its own and make the skirts of different fabrics alike. The rest state found
/// afterwards does not depend on the damping, only the fold branch it lands on.
struct Settling {
    double dt = 1.0 / 60.0;     ///< implicit Euler time step [s]
    double duration = 1.5;      ///< simulated time of the fall [s]; <= 0 skips it
    double damping_rate = 20.0; ///< air damping rate during the fall [1/s] (velocity time constant 50 ms)
    int iterations = 3;         ///< Newton iterations per implicit step
};

/// Brings a garment scene to rest by the path a fitting room would see: a skirt
/// settles from its flat pattern (`settling`), then the static solver finds the
/// rest state from there; other garments and tablecloths go straight to the
/// static solve. Returns the solver status (iterations and wall time include the
/// fall). Never throws on numerical trouble; cancellation and progress through
/// `opt`. The model's own air damping is restored after the fall.
cloth::SolverStatus drape_to_rest(Scene& scene, const cloth::RestOptions& opt, const Settling& settling = {});

/// The skirt's path to rest on its system alone (what drape_to_rest runs for a
/// skirt): the settling fall from the current state, then the static solve.
cloth::SolverStatus settle_to_rest(cloth::ClothSystem& system, const cloth::RestOptions& opt, const Settling& settling = {});

/// Rest options of a garment drape: the static solver (each Newton iteration one
/// sparse Cholesky) with a residual the eye cannot tell from exact rest.
cloth::RestOptions garment_rest_options();

} // namespace drape::importers
