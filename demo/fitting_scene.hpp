#pragma once
// The fitting scenes of the demo app, free of any GUI: a mannequin imported
// through assimp and stood on the floor, a circular skirt generated around its
// waist, a round tablecloth on a round table, and the cloth systems that drape
// them with a fabric preset. The GUI (fitting_view, main_window) and the tests
// use the same functions, so what the test checks is what the user sees.
//
// World frame: Drapekit's (z up, metres). The mannequin stands on the floor
// z = 0, centred on the z axis; the table stands on the floor too.
#include "engine/cloth/fabric_io.hpp"
#include "engine/cloth/solver.hpp"
#include "engine/cloth/system.hpp"
#include "importers/mesh_collider.hpp"
#include "importers/mesh_import.hpp"

#include <memory>
#include <string>
#include <vector>

namespace drape::demo {

/// The demo's default mannequin: the MakeHuman body of Debian's assimp-testmodels (BSD-3).
std::string default_mannequin_path();

/// An imported body, moved so that its feet touch z = 0 and its bounding box is
/// centred on the z axis.
struct Mannequin {
    std::string path;
    importers::ImportedMesh mesh;                       ///< merged meshes, world frame [m]
    std::shared_ptr<const importers::MeshCollider> collider; ///< the body surface itself (offset 0): for checks
    /// What the cloth touches: the body with a padding of kContactPadding, so a
    /// cloth pulled tight over the hips (whose penalty contact gives a little
    /// under tension) still ends outside the body itself.
    std::shared_ptr<const importers::MeshCollider> contact;
    static constexpr double kContactPadding = 2e-3; ///< [m]
    importers::AlignedBox bounds;                       ///< after moving [m]
    double height() const { return bounds.max.z() - bounds.min.z(); } ///< [m]
};

/// Imports `path` (units / up axis as in `opt`; the file's own by default) and
/// stands it on the floor. Throws FileError/ParameterError from the importer,
/// and ParameterError when the body is not 0.5..2.5 m tall (a wrong unit).
Mannequin load_mannequin(const std::string& path, const importers::ImportOptions& opt = {});

/// Horizontal cross-section of the torso at height z [m].
struct Girth {
    double z = 0;                 ///< [m]
    Eigen::Vector2d centre{0, 0}; ///< [m] torso centre (x, y)
    double max_radius = 0;        ///< [m] farthest torso surface from the centre
    double mean_radius = 0;       ///< [m]
    int rays_hit = 0;             ///< of the rays cast (a closed torso section is hit by all)
    int rays = 0;
};

/// Casts `rays` horizontal rays from the torso centre at height z and keeps the
/// first surface each meets, so arms and hands beside the torso are ignored.
/// The centre is the midpoint of the section's extent along x and y within the
/// middle of the body (|x| < 15 % of the height).
Girth measure_girth(const Mannequin& m, double z, int rays = 180);

/// The waist: the narrowest torso section between 56 % and 66 % of the body
/// height (MakeHuman and anthropometric tables put the natural waist near
/// 61-63 % of stature).
Girth find_waist(const Mannequin& m);

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

/// Garment choice.
enum class Garment { Skirt, Tablecloth };
Garment parse_garment(const std::string& name); ///< "skirt" | "tablecloth"; ParameterError otherwise
std::string to_string(Garment g);

/// A round table standing on the floor.
struct Table {
    double radius = 0.45;     ///< [m]
    double height = 0.75;     ///< [m] top above the floor
    double cloth_diameter = 1.5; ///< [m] round tablecloth
};

/// Sizes of the generated skirt, relative to the measured waist.
struct SkirtOptions {
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
    Girth waist;                                ///< skirt only
    std::string fabric_name;
};

/// Skirt on the mannequin: annulus around the measured waist, waistband pinned,
/// colliders = body (MeshCollider) + floor. FabricParams are required; a seed
/// preset is converted with cloth::continuum_from_seed.
Scene make_skirt_scene(std::shared_ptr<const Mannequin> m, const cloth::FabricPreset& fabric,
                       const SkirtOptions& opt = {});
/// Round tablecloth centred on a round table: colliders = table top (a
/// PedestalCollider: top radius, height) + floor; a small symmetry-breaking
/// lift as in the drapemeter so folds can form.
Scene make_tablecloth_scene(const cloth::FabricPreset& fabric, const Table& table = {}, int grid = 45,
                            std::uint64_t seed = 1);

/// Rest options the demo uses: the static solver (each Newton iteration one
/// sparse Cholesky) with a residual the eye cannot tell from exact rest.
cloth::RestOptions demo_rest_options();

/// Smallest signed distance of the cloth's vertices to the body surface [m]
/// (negative = a vertex inside the body) and the number of vertices inside.
struct Penetration {
    double min_distance = 0;
    int inside = 0;
    int worst_vertex = -1;
};
Penetration body_penetration(const Mannequin& m, const cloth::Positions& x);

/// Fabric choices: the user's library (engine/library), then the starter
/// presets shipped in data/library, then the built-in seed Table 1 preset.
struct FabricChoice {
    std::string name;   ///< display name
    std::string origin; ///< "library", "starter", "built-in", "fitted"
    cloth::FabricPreset preset;
};
/// `library_path` empty = the default library; a missing library is skipped.
/// Never throws: unreadable entries are left out and reported in `warnings`.
std::vector<FabricChoice> available_fabrics(const std::string& library_path, const std::string& starter_dir,
                                            std::vector<std::string>* warnings = nullptr);

} // namespace drape::demo
