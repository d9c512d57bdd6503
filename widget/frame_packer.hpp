#pragma once
// The one frame packer: a triangle mesh's world positions [m] -> the buffers a
// MeshGeometry uploads (scene positions, smooth normals, texture coordinates,
// interleaved; uint32 triangle indices). Pure functions with no Qt Quick object,
// so a worker thread packs while the GUI thread draws the previous frame.
#include "widget/drape_widget_export.hpp"
#include "engine/cloth/mesh.hpp"

#include <QByteArray>
#include <QVector3D>

#include <vector>

namespace drape::widget {

/// Floats per vertex in PackedVertices::data: scene position (3), smooth scene
/// normal (3), texture coordinate (2).
inline constexpr int kFloatsPerVertex = 8;

/// Triangles as the GPU reads them (constant while a mesh keeps its topology).
struct PackedTopology {
    QByteArray indices;    ///< 3 uint32 per triangle
    int vertexCount = 0;
    int triangleCount = 0;
};

/// One state of a mesh, interleaved (kFloatsPerVertex floats per vertex).
struct PackedVertices {
    QByteArray data;
    QVector3D boundsMin, boundsMax; ///< scene [m]
    int vertexCount = 0;
};

DRAPE_WIDGET_EXPORT PackedTopology packTopology(const cloth::Triangles& F, int vertexCount);

/// Material coordinates [m] (n x 2) -> texture coordinates in [0, 1], the same
/// scale on both axes, so an image (e.g. a record's top photo cropped to the
/// specimen) covers the sheet once. Zeros when `uv` does not have n rows.
DRAPE_WIDGET_EXPORT std::vector<float> texcoordsFromMaterial(const Eigen::MatrixX2d& uv, int n);

/// Positions [m] (world, z up) -> scene positions, area-weighted smooth normals
/// and the texture coordinates (2 per vertex, or empty for zeros).
DRAPE_WIDGET_EXPORT PackedVertices packVertices(const cloth::Positions& X, const cloth::Triangles& F, const std::vector<float>& texcoord);

} // namespace drape::widget
