#pragma once
// The drapemeter the controller shows: what to build (DrapeSpec), building it
// with the engine (the disc is cloth::make_drape_system's; the square sheet gets
// the same start, lift and colliders through cloth::place_on_drapemeter), and
// the colliders as drawable primitives.
#include "widget/drape_frame.hpp"

#include "engine/cloth/drape.hpp"
#include "engine/fabric/preset.hpp"

#include <QString>

#include <memory>
#include <vector>

namespace drape::widget {

/// Everything needed to build a cloth scene.
struct DrapeSpec {
    fabric::FabricPreset preset;
    QString presetName;          ///< as given by the user (path or built-in name)
    cloth::DrapeSetup setup;     ///< diameters [m], grid, floor ...
    QString shape = "disc";      ///< "disc" (drapemeter specimen) or "square" (sheet of side sample diameter)
};

struct SphereSpec {
    Eigen::Vector3d centre; ///< world [m]
    double radius;          ///< [m]
};

/// The cloth system of `spec` at its perturbed flat start, with the pedestal and
/// floor colliders. Throws drape::Error on bad input.
std::unique_ptr<cloth::ClothSystem> makeDrapeSystem(const DrapeSpec& spec);

/// The fastest free (unpinned) vertex [m/s].
double maxFreeSpeed(const cloth::ClothSystem& s);

/// Drawable shapes of a collider tree (pedestal, planes, spheres, groups).
void describeColliders(const cloth::Collider& c, std::vector<ColliderShape>& out);

} // namespace drape::widget
