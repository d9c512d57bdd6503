#pragma once
// What the controller shows: what to build (DrapeSpec), building it with the
// engine, and the colliders as drawable primitives. The drapemeter disc is
// cloth::make_drape_system's (the square sheet gets the same start, lift and
// colliders through cloth::place_on_drapemeter); the skirt and the tablecloth
// are importers::make_skirt_scene / make_tablecloth_scene; a host's garment mesh
// becomes cloth through cloth::make_triangle_mesh and drapes on the body (a
// MeshCollider) and the floor. Built on the worker thread: importing a body or
// measuring its waist never holds up the GUI.
#include "widget/drape_enums.hpp"
#include "widget/drape_frame.hpp"

#include "engine/cloth/drape.hpp"
#include "engine/fabric/preset.hpp"
#include "importers/body.hpp"

#include <QString>

#include <memory>
#include <vector>

namespace drape::widget {

/// A garment mesh a host gives: rest shape and start positions X [m] (n x 3,
/// world frame, z up), triangles F, and the vertices held where they are (a
/// waistband, shoulder seams). Material coordinates come from the best-fit
/// plane with the warp along `warp` (cloth::make_triangle_mesh).
struct GarmentMesh {
    cloth::Positions X;
    cloth::Triangles F;
    std::vector<int> pinned;
    Eigen::Vector3d warp = Eigen::Vector3d::UnitX();
};

/// Everything needed to build a cloth scene.
struct DrapeSpec {
    fabric::FabricPreset preset;
    QString presetName;          ///< as given by the user (path, library name, built-in)
    cloth::DrapeSetup setup;     ///< drapemeter: diameters [m], grid, floor ...
    Drape::ClothShape shape = Drape::Disc;
    /// The body: a host's (set in C++), else imported from `bodyFile` on the worker (empty = none).
    std::shared_ptr<const importers::Mannequin> body;
    QString bodyFile;
    /// GarmentMesh: a host's mesh, else imported from `garmentFile` on the worker.
    std::shared_ptr<const GarmentMesh> garment;
    QString garmentFile;
};

/// A garment imported from a mesh file (assimp; all meshes merged, welded) with
/// its top boundary pinned: the boundary vertices within 1 cm of the highest one.
GarmentMesh loadGarmentMesh(const std::string& path);

struct SphereSpec {
    Eigen::Vector3d centre; ///< world [m]
    double radius;          ///< [m]
};

/// The cloth system of `spec` at its start: the drapemeter's perturbed flat
/// start with the pedestal and floor colliders; a skirt, a tablecloth or the
/// garment mesh with the body (if any) and the floor. `body` is the body in use
/// (the spec's, imported, or the default mannequin for a skirt). Throws
/// drape::Error on bad input.
std::unique_ptr<cloth::ClothSystem> makeDrapeSystem(const DrapeSpec& spec,
                                                    const std::shared_ptr<const importers::Mannequin>& body);

/// The fastest free (unpinned) vertex [m/s].
double maxFreeSpeed(const cloth::ClothSystem& s);

/// Drawable shapes of a collider tree (pedestal, planes, spheres, groups).
void describeColliders(const cloth::Collider& c, std::vector<ColliderShape>& out);

} // namespace drape::widget
