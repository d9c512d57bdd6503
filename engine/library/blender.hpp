#pragma once
// A fabric preset as Blender cloth settings, for artists: a Python script that
// sets the Cloth modifier of the selected mesh object from the preset's SI
// parameters and that object's own mesh (Blender's spring constants depend on
// the edge length and its vertex mass on the vertex count; the script measures
// both). One way: Blender's cloth is not read back.
//
// The mapping, for a quad mesh of mean edge length h [m] (derivation in
// docs/library.md, "Blender"; source: Blender's SIM_mass_spring.cc):
//   vertex mass [kg]         = areal density * mesh area / vertex count   (= rho h^2 on a regular grid)
//   tension = compression    = 0.001 * (stretch_warp + stretch_weft) / 2 * h
//   shear                    = 0.001 * shear * h
//   bending (angular model)  = 0.01 * (bend_warp + bend_weft) / 2 / h^2
//   collision distance [m]   = thickness / 2 (at least Blender's 1 mm)
// The factor 0.001 is Blender's: its cloth solver scales gravity by 0.001, so
// every stiffness is scaled alike to keep the rest shape (which only depends on
// stiffness over weight). Blender's cloth is isotropic: warp and weft are averaged.
#include "engine/fabric/preset.hpp"

#include <string>

namespace drape::library {

/// Blender's cloth settings for a quad mesh of mean edge length `edge_m` [m].
struct BlenderCloth {
    double edge_m = 0;            ///< [m]
    double vertex_mass_kg = 0;    ///< Cloth > Physical Properties > Vertex Mass (regular grid: rho h^2)
    double tension = 0;           ///< Stiffness > Tension
    double compression = 0;       ///< Stiffness > Compression
    double shear = 0;             ///< Stiffness > Shear
    double bending = 0;           ///< Stiffness > Bending (bending model: Angular)
    double collision_distance_m = 0; ///< Collisions > Object Collisions > Distance
};
BlenderCloth blender_cloth(const fabric::FabricPreset& preset, double edge_m);

/// The Python script (run it in Blender's Text Editor with the garment selected,
/// or `blender file.blend --python script.py`).
std::string preset_to_blender_script(const fabric::FabricPreset& preset);

} // namespace drape::library
