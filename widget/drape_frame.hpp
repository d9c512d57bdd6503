#pragma once
// Data the drapemeter worker hands to the UI thread. Every object is built by
// the worker and never touched again after it is emitted (shared_ptr<const>),
// so the UI reads a private copy while the worker keeps simulating.
#include "widget/drape_enums.hpp"
#include "widget/frame_packer.hpp"
#include "widget/world_frame.hpp"

#include "engine/cloth/drape.hpp"
#include "engine/cloth/mesh.hpp"
#include "engine/cloth/metrics.hpp"
#include "engine/cloth/solver.hpp"
#include "importers/body.hpp"

#include <QMetaType>
#include <QString>
#include <QVector3D>

#include <memory>
#include <optional>
#include <vector>

namespace drape::widget {

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
    std::vector<float> texcoord; ///< 2 per vertex, material coordinates scaled to [0, 1]
    std::vector<char> boundary;  ///< hem vertices
    std::vector<ColliderShape> colliders;
    double sampleRadius = 0;   ///< [m]
    double discRadius = 0;     ///< [m]
    QString description;       ///< fabric name and grid, for the status line
    Drape::ClothShape shape = Drape::Disc;
    std::shared_ptr<const importers::Mannequin> body; ///< drawn and collided with (null = none)
    std::vector<int> pinnedAtStart; ///< vertices the shape pins (a waistband), increasing
    Eigen::Vector3d boundsMin = Eigen::Vector3d::Zero(); ///< cloth start and body [m], for the camera
    Eigen::Vector3d boundsMax = Eigen::Vector3d::Zero();
};

/// One state of the cloth.
struct DrapeFrame {
    int generation = 0;
    cloth::Positions x;        ///< world positions [m], n x 3
    PackedVertices vertices;   ///< x packed for the GPU (packVertices)
    std::vector<int> pinned;   ///< pinned vertex indices, increasing
    double simTime = 0;        ///< [s]
    long steps = 0;
    double maxSpeed = 0;       ///< [m/s] over free vertices
    cloth::Polygon2 outline;   ///< simulated shadow outline [m] (empty unless requested)
    std::shared_ptr<const Eigen::VectorXd> mass; ///< [kg] per vertex (shared until a mass changes)
    double fraction = -1;      ///< a drape to rest: progress in [0, 1], negative = not resting / unknown
    QString status;            ///< a drape to rest: "Newton iteration 12, residual 3e-4"
};

/// The rest state's results, computed on the worker when the cloth came to rest.
struct DrapeResults {
    int generation = 0;
    cloth::SolverStatus status;       ///< the static solve's (dynamic: outcome Converged, steps, time)
    cloth::Positions x;               ///< rest positions [m], n x 3
    /// Drapemeter shapes: the engine's drape metrics (measure_drape: D, nodes, radii, hem, slices).
    std::optional<cloth::DrapeResult> drape;
    /// With a body: the cloth's closest approach to the body surface (negative = inside).
    std::optional<importers::Penetration> penetration;
};

using DrapeMeshPtr = std::shared_ptr<const DrapeMeshData>;
using DrapeFramePtr = std::shared_ptr<const DrapeFrame>;
using DrapeResultsPtr = std::shared_ptr<const DrapeResults>;

} // namespace drape::widget

Q_DECLARE_METATYPE(drape::widget::DrapeMeshPtr)
Q_DECLARE_METATYPE(drape::widget::DrapeFramePtr)
Q_DECLARE_METATYPE(drape::widget::DrapeResultsPtr)
