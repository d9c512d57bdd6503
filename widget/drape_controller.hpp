#pragma once
// DrapeController: the drapemeter view's state and commands, shared by the
// QWidget (DrapeView) and the QML scene (Drapekit.DrapeScene). It owns the
// worker thread that runs the engine and the long-job runner, and it is a
// client of a Scene: the cloth is a SceneMesh the worker's frames update, the
// colliders are primitives, the outlines and floor boards geometry items, the
// pins markers.
//
// Units: sampleDiameter and discDiameter are in millimetres (the lab's and a
// CAD user's unit); everything else is SI (timeStep [s], restSpeed [m/s],
// masses [kg], collider positions [m] in Drapekit's world frame: z up, origin
// at the pedestal top centre).
#include "widget/drape_frame.hpp"
#include "widget/drape_properties.hpp"
#include "widget/floor_boards.hpp"
#include "widget/line_geometry.hpp"
#include "widget/long_job.hpp"
#include "widget/scene.hpp"

#include "engine/fabric/preset.hpp"

#include <QImage>
#include <QObject>
#include <QPointF>
#include <QPolygonF>
#include <QSet>
#include <QThread>
#include <QVariantList>

#include <vector>

namespace drape::widget {

class DrapeWorker;

class DrapeController : public QObject {
    Q_OBJECT
    // ---- designable (drape_properties.hpp; DrapeView has the same) ---------------
    DRAPE_VIEW_PROPERTIES(DRAPE_DECLARE_Q_PROPERTY)
    // ---- what the view draws and reports --------------------------------------
    Q_PROPERTY(drape::widget::Scene* scene READ scene CONSTANT)
    Q_PROPERTY(drape::widget::MeshGeometry* clothGeometry READ clothGeometry CONSTANT)
    Q_PROPERTY(drape::widget::LineGeometry* simulatedOutline READ simulatedOutline CONSTANT)
    Q_PROPERTY(drape::widget::LineGeometry* measuredOutline READ measuredOutline CONSTANT)
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

    Scene* scene() const { return m_scene; }
    MeshGeometry* clothGeometry() const { return m_cloth->meshGeometry(); }
    LineGeometry* simulatedOutline() const { return m_simOutline; }
    LineGeometry* measuredOutline() const { return m_measOutline; }
    bool hasTexture() const { return m_cloth->textured(); }
    QVariantList colliders() const { return m_colliders; }
    QVariantList pinnedPositions() const { return m_pinnedPositions; }
    QVector3D cameraPosition() const { return m_scene->cameraPosition(); }
    QQuaternion cameraRotation() const { return m_scene->cameraRotation(); }
    double fieldOfView() const { return m_scene->fieldOfView(); }
    int vertexCount() const;
    double simulatedTime() const;
    QString statusText() const;
    bool jobRunning() const { return m_job.running(); }

    const OrbitCamera& camera() const { return m_scene->camera(); }
    OrbitCamera& camera() { return m_scene->camera(); }
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
    Q_INVOKABLE void orbit(double dxPixels, double dyPixels) { m_scene->orbit(dxPixels, dyPixels); }
    Q_INVOKABLE void pan(double dxPixels, double dyPixels, double viewHeight) { m_scene->pan(dxPixels, dyPixels, viewHeight); }
    Q_INVOKABLE void zoom(double wheelDelta) { m_scene->zoom(wheelDelta); }
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
    void scheduleRebuild();
    void rebuildNow();
    void onMesh(const DrapeMeshPtr& mesh);
    void onFrame(const DrapeFramePtr& frame);
    void onWorkerRunning(bool on);
    void showColliders(const std::vector<ColliderShape>& shapes);
    void updateVisibility();
    void updatePinnedPositions();
    void fail(const QString& message);
    QObject* workerObject() const;
    /// Runs `f` on the worker's thread, after the commands sent before.
    template <class F>
    void toWorker(F&& f)
    {
        QMetaObject::invokeMethod(workerObject(), std::forward<F>(f), Qt::QueuedConnection);
    }

    DrapeSettings m_settings;
    fabric::FabricPreset m_preset;
    bool m_rebuildPending = false;

    Scene* m_scene = nullptr;
    SceneMesh* m_cloth = nullptr;
    LineGeometry* m_simOutline = nullptr;
    LineGeometry* m_measOutline = nullptr;
    FloorBoardsGeometry* m_floorBoards = nullptr;
    bool m_hasFloor = false;
    QStringList m_colliderItems; ///< scene item names of the drawn colliders
    QVariantList m_colliders;
    QVariantList m_pinnedPositions;
    QSet<int> m_pinned;
    DrapeMeshPtr m_mesh;
    DrapeFramePtr m_frame;
    QThread m_thread;
    DrapeWorker* m_worker = nullptr;
    LongJob m_job;
};

} // namespace drape::widget
