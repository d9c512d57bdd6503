#pragma once
// DrapeController: the state and commands of a drape view, shared by the
// QWidget (DrapeView) and the QML scene (Drapekit.DrapeScene). It owns the
// worker thread that runs the engine, the Qt Quick 3D geometry objects, the
// orbit camera, the texture and the long-job runner.
//
// Units: sampleDiameter and discDiameter are in millimetres (the lab's and a
// CAD user's unit); everything else is SI (timeStep [s], restSpeed [m/s],
// masses [kg], collider positions [m] in Drapekit's world frame: z up, origin
// at the pedestal top centre).
#include "widget/cloth_geometry.hpp"
#include "widget/drape_frame.hpp"
#include "widget/drape_properties.hpp"
#include "widget/floor_boards.hpp"
#include "widget/line_geometry.hpp"
#include "widget/long_job.hpp"
#include "widget/orbit_camera.hpp"

#include "engine/fabric/preset.hpp"

#include <QColor>
#include <QImage>
#include <QObject>
#include <QPointF>
#include <QPolygonF>
#include <QQuick3DTextureData>
#include <QQuaternion>
#include <QSet>
#include <QThread>
#include <QVariantList>
#include <QVector3D>

#include <memory>

namespace drape::widget {

class DrapeWorker;

class DrapeController : public QObject {
    Q_OBJECT
    // ---- designable (drape_properties.hpp; DrapeView has the same) ---------------
    DRAPE_VIEW_PROPERTIES(DRAPE_DECLARE_Q_PROPERTY)
    // ---- for the QML scene ----------------------------------------------------
    Q_PROPERTY(drape::widget::ClothGeometry* clothGeometry READ clothGeometry CONSTANT)
    Q_PROPERTY(drape::widget::LineGeometry* simulatedOutline READ simulatedOutline CONSTANT)
    Q_PROPERTY(drape::widget::LineGeometry* measuredOutline READ measuredOutline CONSTANT)
    Q_PROPERTY(QQuick3DTextureData* textureData READ textureData CONSTANT)
    Q_PROPERTY(drape::widget::FloorBoardsGeometry* floorBoards READ floorBoards CONSTANT)
    /// labFloor and the scene has a horizontal floor to draw the boards on.
    Q_PROPERTY(bool floorBoardsVisible READ floorBoardsVisible NOTIFY labFloorChanged)
    Q_PROPERTY(bool hasTexture READ hasTexture NOTIFY textureChanged)
    Q_PROPERTY(QVariantList colliders READ colliders NOTIFY collidersChanged)
    Q_PROPERTY(QVariantList pinnedPositions READ pinnedPositions NOTIFY pinnedChanged)
    Q_PROPERTY(QVector3D cameraPosition READ cameraPosition NOTIFY cameraChanged)
    Q_PROPERTY(QQuaternion cameraRotation READ cameraRotation NOTIFY cameraChanged)
    Q_PROPERTY(double fieldOfView READ fieldOfView NOTIFY cameraChanged) ///< vertical [deg]
    Q_PROPERTY(int vertexCount READ vertexCount NOTIFY meshChanged)
    Q_PROPERTY(double simulatedTime READ simulatedTime NOTIFY frameApplied) ///< [s]
    Q_PROPERTY(QString statusText READ statusText NOTIFY frameApplied)
    Q_PROPERTY(bool jobRunning READ jobRunning NOTIFY jobRunningChanged)

public:
    explicit DrapeController(QObject* parent = nullptr);
    ~DrapeController() override;

    // Getters and setters of the designable properties: fabricPreset() /
    // setFabricPreset(const QString&), sampleDiameter() / setSampleDiameter(double) ...
#define DRAPE_CONTROLLER_ACCESSORS(Type, Arg, name, setter, init) \
    Type name() const { return m_settings.name; }                 \
    void setter(Arg value);
    DRAPE_VIEW_PROPERTIES(DRAPE_CONTROLLER_ACCESSORS)
#undef DRAPE_CONTROLLER_ACCESSORS
    FloorBoardsGeometry* floorBoards() const { return m_floorBoards; }
    bool floorBoardsVisible() const { return m_settings.labFloor && m_hasFloor; }

    ClothGeometry* clothGeometry() const { return m_cloth; }
    LineGeometry* simulatedOutline() const { return m_simOutline; }
    LineGeometry* measuredOutline() const { return m_measOutline; }
    QQuick3DTextureData* textureData() const { return m_textureData; }
    bool hasTexture() const { return m_hasTexture; }
    QVariantList colliders() const { return m_colliders; }
    QVariantList pinnedPositions() const { return m_pinnedPositions; }
    QVector3D cameraPosition() const { return m_camera.scenePosition(); }
    QQuaternion cameraRotation() const { return m_camera.sceneRotation(); }
    double fieldOfView() const { return m_camera.fovYDegrees(); }
    int vertexCount() const;
    double simulatedTime() const;
    QString statusText() const;
    bool jobRunning() const { return m_job.running(); }

    const OrbitCamera& camera() const { return m_camera; }
    OrbitCamera& camera() { return m_camera; }
    /// Latest frame shown (may be null before the first one).
    DrapeFramePtr currentFrame() const { return m_frame; }
    DrapeMeshPtr currentMesh() const { return m_mesh; }
    /// The fabric preset in use (as loaded, with edits from setFabricParameter).
    const fabric::FabricPreset& preset() const { return m_preset; }

    /// Runs `fn` on a worker thread with progress and cancel (see LongJob): the
    /// hook for fitting a preset to a record. False when a job is running.
    bool startJob(const QString& name, JobFunction fn);

    /// Shows a measured outline (polygon in the horizontal plane [m], world frame)
    /// over the simulated one; turns showOutlines on.
    void showMeasuredOutline(const QPolygonF& outlineMetres);

public slots:
    void play();
    void pause();
    void step();
    void reset();
    /// Builds the cloth now from the current properties (they otherwise rebuild
    /// on the next event-loop turn after a change).
    void createCloth();
    void cancelJob();
    void clearMeasuredOutline();
    void clearPins();
    void clearExtraColliders();

public:
    // ---- interaction (QML-callable) -------------------------------------------
    Q_INVOKABLE void orbit(double dxPixels, double dyPixels);
    Q_INVOKABLE void pan(double dxPixels, double dyPixels, double viewHeight);
    Q_INVOKABLE void zoom(double wheelDelta);
    /// Vertex under view point (x, y) of a w x h view, or -1.
    Q_INVOKABLE int pickVertex(double x, double y, double w, double h) const;
    /// Pins the vertex under the point, or unpins it when pinned. Returns it (-1 = none).
    Q_INVOKABLE int togglePinAt(double x, double y, double w, double h);
    Q_INVOKABLE void setPinned(int vertex, bool pinned);
    Q_INVOKABLE bool isPinned(int vertex) const { return m_pinned.contains(vertex); }
    Q_INVOKABLE QList<int> pinnedVertices() const;
    /// Pinned vertices as the simulation last reported them.
    Q_INVOKABLE QList<int> simulatedPinnedVertices() const;
    Q_INVOKABLE void setVertexMass(int vertex, double kg);
    Q_INVOKABLE double vertexMass(int vertex) const; ///< [kg], NaN when unknown
    /// World point [m] -> view point of a w x h view (NaN when behind the camera).
    Q_INVOKABLE QPointF projectToView(const QVector3D& worldMetres, double w, double h) const;
    Q_INVOKABLE void addSphereCollider(const QVector3D& centreMetres, double radiusMetres);
    /// Writes state + results: `jsonPath` and an OBJ next to it (same base name).
    /// Asynchronous: resultsSaved or errorOccurred follows.
    Q_INVOKABLE void saveResults(const QString& jsonPath);
    Q_INVOKABLE bool saveFabricPreset(const QString& path);
    Q_INVOKABLE bool loadFabricPreset(const QString& path) { return applyFabricPreset(path); }
    /// The parameter table with the current values: list of {key, unit, value,
    /// lower, upper, defaultValue, doc, editable}.
    Q_INVOKABLE QVariantList fabricParameters() const;
    Q_INVOKABLE bool setFabricParameter(const QString& key, double value);
    /// QML form of showMeasuredOutline: a list of points (x, y) [m].
    Q_INVOKABLE void setMeasuredOutline(const QVariantList& points);
    /// Uses an in-memory image as texture (e.g. the record's top photo).
    Q_INVOKABLE bool setTextureImage(const QImage& image);

signals:
    DRAPE_VIEW_PROPERTIES(DRAPE_DECLARE_CHANGED_SIGNAL)
    DRAPE_VIEW_SIGNALS(DRAPE_DECLARE_SIGNAL)
    void collidersChanged();
    void pinnedChanged();
    void cameraChanged();
    void meshChanged();
    void frameApplied();
    void fabricParametersChanged();
    void jobStarted(const QString& name);
    void jobRunningChanged();

private:
    bool applyFabricPreset(const QString& preset);
    void uploadTexture(const QImage& image);
    void rebuildColliderList();
    void scheduleRebuild();
    void rebuildNow();
    void onMesh(const DrapeMeshPtr& mesh);
    void onFrame(const DrapeFramePtr& frame);
    void onWorkerRunning(bool on);
    void updatePinnedPositions();
    void fail(const QString& message);
    template <class F>
    void toWorker(F&& f);

    DrapeSettings m_settings;
    fabric::FabricPreset m_preset;
    bool m_hasTexture = false;
    bool m_rebuildPending = false;

    OrbitCamera m_camera;
    ClothGeometry* m_cloth = nullptr;
    LineGeometry* m_simOutline = nullptr;
    LineGeometry* m_measOutline = nullptr;
    QQuick3DTextureData* m_textureData = nullptr;
    FloorBoardsGeometry* m_floorBoards = nullptr;
    bool m_hasFloor = false;
    QVariantList m_colliders;
    std::vector<ColliderShape> m_colliderShapes;
    QVariantList m_pinnedPositions;
    QSet<int> m_pinned;
    DrapeMeshPtr m_mesh;
    DrapeFramePtr m_frame;
    QThread m_thread;
    DrapeWorker* m_worker = nullptr;
    LongJob m_job;
};

} // namespace drape::widget
