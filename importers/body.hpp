#pragma once
// A mannequin for fittings: a body imported through assimp, stood on the
// floor, with its torso sections (girth, waist) and a penetration check for
// cloth on it. No GUI: the demo, the widget and `drape garment` share it.
//
// World frame: Drapekit's (z up, metres). The mannequin stands on the floor
// z = 0, centred on the z axis.
#include "importers/mesh_collider.hpp"
#include "importers/mesh_import.hpp"

#include "engine/cloth/mesh.hpp"

#include <memory>
#include <string>

namespace drape::importers {

/// The default mannequin: the MakeHuman body of Debian's assimp-testmodels (BSD-3).
std::string default_mannequin_path();

/// An imported body, moved so that its feet touch z = 0 and its bounding box is
/// centred on the z axis.
struct Mannequin {
    std::string path;
    ImportedMesh mesh;                       ///< merged meshes, world frame [m]
    std::shared_ptr<const MeshCollider> collider; ///< the body surface itself (offset 0): for checks
    /// What the cloth touches: the body with a padding of kContactPadding, so a
    /// cloth pulled tight over the hips (whose penalty contact gives a little
    /// under tension) still ends outside the body itself.
    std::shared_ptr<const MeshCollider> contact;
    static constexpr double kContactPadding = 2e-3; ///< [m]
    AlignedBox bounds;                       ///< after moving [m]
    double height() const { return bounds.max.z() - bounds.min.z(); } ///< [m]
};

/// Imports `path` (units / up axis as in `opt`; the file's own by default) and
/// stands it on the floor. Throws FileError/ParameterError from the importer,
/// and ParameterError when the body is not 0.5..2.5 m tall (a wrong unit).
Mannequin load_mannequin(const std::string& path, const ImportOptions& opt = {});

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

/// Smallest signed distance of the cloth's vertices to the body surface [m]
/// (negative = a vertex inside the body) and the number of vertices inside.
struct Penetration {
    double min_distance = 0;
    int inside = 0;
    int worst_vertex = -1;
};
Penetration body_penetration(const Mannequin& m, const cloth::Positions& x);

} // namespace drape::importers
