#pragma once
// Mesh import through assimp (OBJ, Collada/ZAE, glTF, FBX, PLY, STL and the other
// formats assimp reads) into the engine's frame: metres, z up, right-handed.
//
// Units and up axis are explicit. `Unit::File` / `UpAxis::File` use what the file
// declares (Collada <unit>/<up_axis>, FBX UnitScaleFactor/UpAxis, glTF is metres
// and y up by its specification) and fall back to metres / y up for formats that
// declare nothing (OBJ, PLY, STL); ImportedScene says which one was used. An
// explicit unit or axis describes the numbers as they are written in the file
// and overrides whatever the file declares.
//
// Scene-graph node transforms are applied (a mesh instanced by two nodes comes
// out twice). Vertices at identical positions are welded, because normal and
// texture seams split them in most files and a collider needs the connectivity.
#include "engine/cloth/mesh.hpp"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace drape::importers {

enum class Unit { File, Millimetre, Centimetre, Metre };
enum class UpAxis { File, Y, Z };

/// Parses "mm", "cm", "m" (and "file"/"auto"). Throws ParameterError naming `what`.
Unit parse_unit(const std::string& text, const std::string& what = "unit");
/// Parses "y", "z" (and "file"/"auto"). Throws ParameterError naming `what`.
UpAxis parse_up_axis(const std::string& text, const std::string& what = "up axis");
std::string to_string(Unit u);
std::string to_string(UpAxis a);

struct ImportOptions {
    Unit unit = Unit::File;
    UpAxis up = UpAxis::File;
    bool weld = true; ///< merge vertices at exactly the same position
};

struct AlignedBox {
    Eigen::Vector3d min = Eigen::Vector3d::Constant(0.0); ///< [m]
    Eigen::Vector3d max = Eigen::Vector3d::Constant(0.0); ///< [m]
    Eigen::Vector3d size() const { return max - min; }
};

/// One mesh instance of the scene, triangles only, in the engine's frame.
struct ImportedMesh {
    std::string name;      ///< mesh name, else node name, else "mesh<N>"
    cloth::Positions X;    ///< n x 3 [m], z up
    cloth::Triangles F;    ///< m x 3, winding as in the file (outward for closed bodies)
    int vertex_count() const { return static_cast<int>(X.rows()); }
    int triangle_count() const { return static_cast<int>(F.rows()); }
    AlignedBox bounds() const;
};

struct ImportedScene {
    std::string path;
    std::vector<ImportedMesh> meshes;
    double unit_scale = 1.0;       ///< metres per file unit that was applied
    std::string unit_source;       ///< "option", "file" or "assumed"
    UpAxis up = UpAxis::Y;         ///< the file's up axis that was converted from
    std::string up_source;         ///< "option", "file" or "assumed"
    std::string format;            ///< assimp's importer name

    int vertex_count() const;
    int triangle_count() const;
    AlignedBox bounds() const;
    /// All meshes in one (indices shifted), named after the file.
    ImportedMesh merged() const;
    /// The meshes whose name is in `names`, merged; throws ParameterError
    /// naming the unknown name and listing the available ones.
    ImportedMesh merged(const std::vector<std::string>& names) const;
    const ImportedMesh* find(const std::string& name) const;
};

/// Reads a mesh file. Throws FileError naming the file when it cannot be read,
/// is empty or truncated, has a format assimp does not read, holds no triangle
/// mesh, or has a mesh with non-finite coordinates or no triangles.
ImportedScene import_scene(const std::string& path, const ImportOptions& opt = {});

/// Welds vertices at exactly equal positions and drops triangles that become
/// degenerate (two equal indices). Returns the number of vertices removed.
int weld_vertices(cloth::Positions& X, cloth::Triangles& F);

} // namespace drape::importers
