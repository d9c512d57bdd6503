#pragma once
// Imported garment meshes as cloth: the same triangle model and fabric preset
// as the grid cloth (engine/cloth/mesh.hpp make_triangle_mesh + model.hpp).
#include "engine/cloth/mesh.hpp"
#include "importers/mesh_import.hpp"

namespace drape::importers {

/// The garment's rest shape as a cloth mesh; material coordinates come from
/// the best-fit plane with u along `warp` (see cloth::make_triangle_mesh).
/// Throws ParameterError on an empty mesh.
cloth::ClothMesh garment_to_cloth(const ImportedMesh& garment, const Eigen::Vector3d& warp = Eigen::Vector3d::UnitX());

} // namespace drape::importers
