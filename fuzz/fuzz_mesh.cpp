// Mesh import (importers::import_scene) through assimp. The first byte picks
// the file extension (assimp chooses its reader by it and by the content); the
// rest is the file. Accepted scenes hold finite, bounded vertices and valid
// triangles.
#include "engine/core/error.hpp"
#include "fuzz_common.hpp"
#include "importers/mesh_import.hpp"

#include <cstdint>

using namespace drape;

DRAPE_FUZZ_TARGET(mesh)(const std::uint8_t* data, std::size_t size)
{
    if (size < 1) return 0;
    static const char* const kExt[] = {"obj", "ply", "stl", "off", "dae", "gltf", "glb", "fbx", "3ds", "x", "ase", "ac"};
    const auto file = fuzz::scratch() / (std::string("mesh.") + kExt[data[0] % 12]);
    fuzz::write_file(file, reinterpret_cast<const char*>(data + 1), size - 1);
    try {
        const importers::ImportedScene s = importers::import_scene(file.string());
        for (const auto& m : s.meshes) {
            fuzz::require(m.X.allFinite() && (m.X.rows() == 0 || m.X.cwiseAbs().maxCoeff() <= 1e4), "vertices finite and within 10 km");
            fuzz::require(m.F.rows() > 0, "a mesh has triangles");
            fuzz::require(m.F.minCoeff() >= 0 && m.F.maxCoeff() < m.X.rows(), "triangle indices in range");
        }
    } catch (const drape::Error&) {
    }
    std::error_code ec;
    std::filesystem::remove(file, ec);
    return 0;
}
