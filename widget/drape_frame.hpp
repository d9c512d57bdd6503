#pragma once
// Data the simulation worker hands to the UI thread. Every object is built by
// the worker and never touched again after it is emitted (shared_ptr<const>),
// so the UI reads a private copy while the worker keeps simulating.
//
// Frames: world coordinates are Drapekit's (z up, metres, origin at the
// pedestal top centre). Scene coordinates are Qt Quick 3D's (y up):
// scene = (x, z, -y), a rotation of -90 degrees about x, one scene unit = 1 m.
#include "engine/cloth/mesh.hpp"
#include "engine/cloth/metrics.hpp"

#include <QByteArray>
#include <QMetaType>
#include <QString>
#include <QVector3D>

#include <memory>
#include <vector>

namespace drape::widget {

/// World (z up) [m] -> Qt Quick 3D scene (y up) [m].
inline QVector3D toScene(double x, double y, double z)
{
    return {float(x), float(z), float(-y)};
}
/// Scene (y up) -> world (z up).
inline void toWorld(const QVector3D& s, double& x, double& y, double& z)
{
    x = s.x();
    y = -double(s.z());
    z = s.y();
}

/// One drawable collider, already in scene coordinates for a built-in Qt Quick 3D
/// primitive ("#Cylinder", "#Sphere", "#Rectangle": 100 units across).
struct ColliderShape {
    QString kind;       ///< "pedestal", "plane", "sphere"
    QString source;     ///< built-in mesh name
    QVector3D position; ///< scene [m]
    QVector3D scale;    ///< primitive scale
    QVector3D normal;   ///< planes: scene normal, used to orient the rectangle
};

/// Constant per cloth (sent once after a rebuild).
struct DrapeMeshData {
    int generation = 0;        ///< increases with every rebuild; frames carry it
    int vertexCount = 0;
    cloth::Triangles F;        ///< triangles (world winding, counter-clockwise from +z at rest)
    QByteArray indexData;      ///< F as uint32 for the GPU
    std::vector<float> texcoord; ///< 2 per vertex, material coordinates scaled to [0, 1]
    std::vector<char> boundary;  ///< hem vertices
    std::vector<ColliderShape> colliders;
    double sampleRadius = 0;   ///< [m]
    double discRadius = 0;     ///< [m]
    double floorZ = 0;         ///< [m] world z of the floor (for outlines), NaN without floor
    QString description;       ///< fabric name and grid, for the status line
};

/// One state of the cloth.
struct DrapeFrame {
    int generation = 0;
    cloth::Positions x;        ///< world positions [m], n x 3
    /// Interleaved per vertex: scene position (3 floats), smooth scene normal
    /// (3 floats), texture coordinate (2 floats): what ClothGeometry uploads.
    QByteArray vertexData;
    QVector3D boundsMin, boundsMax; ///< scene [m]
    std::vector<int> pinned;   ///< pinned vertex indices, increasing
    double simTime = 0;        ///< [s]
    long steps = 0;
    double maxSpeed = 0;       ///< [m/s] over free vertices
    double residual = -1;      ///< relative force residual, -1 when not computed for this frame
    cloth::Polygon2 outline;   ///< simulated shadow outline [m] (empty unless requested)
    std::shared_ptr<const Eigen::VectorXd> mass; ///< [kg] per vertex (shared until a mass changes)
};

using DrapeMeshPtr = std::shared_ptr<const DrapeMeshData>;
using DrapeFramePtr = std::shared_ptr<const DrapeFrame>;

/// Interleaved float layout of DrapeFrame::vertexData.
inline constexpr int kFloatsPerVertex = 8;

} // namespace drape::widget

Q_DECLARE_METATYPE(drape::widget::DrapeMeshPtr)
Q_DECLARE_METATYPE(drape::widget::DrapeFramePtr)
