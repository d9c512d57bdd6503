#pragma once
// DrapeController: the drape view's state and commands, shared by the QWidget
// (DrapeView) and the QML scene (Drapekit.DrapeScene). It owns the worker
// thread that runs the engine and the long-job runner, and it is a client of a
// Scene: the cloth is a SceneMesh the worker's frames update, the body a
// SceneMesh, the colliders primitives, the outlines and floor boards geometry
// items, the pins markers.
//
// What drapes (clothShape): the drapemeter specimen (Disc) or a square sheet;
// the built-in circle skirt on a body; a round tablecloth; or a host's garment
// mesh with its pinned (waist) vertices on a body (bodyFile or setBody). The
// fabric: a typed preset (setFabric) or a name (fabricPreset: a file, a
// fabric-library name, a starter). Run with `running` (the chosen integrator)
// or drapeToRest() (the static solver, with a progress fraction); cancel();
// read back positions() and the metrics (drapeCoefficient, results()).
//
// Units: sampleDiameter and discDiameter are in millimetres (the lab's and a
// CAD user's unit); everything else is SI (timeStep [s], restSpeed [m/s],
// masses [kg], positions [m] in Drapekit's world frame: z up, origin at the
// pedestal top centre; bodies stand on the floor z = 0).
#include "widget/drape_widget_export.hpp"
#include <QtQml/qqmlregistration.h>
#include "widget/drape_enums.hpp"
#include "widget/drape_frame.hpp"
#include "widget/drape_properties.hpp"
#include "widget/drape_setup.hpp"
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
#include <QVariantMap>

#include <vector>

namespace drape::widget {

class DrapeWorker;

class DRAPE_WIDGET_EXPORT DrapeController : public QObject {
    Q_OBJECT
    QML_ELEMENT
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
    /// A drape to rest: progress in [0, 1] (negative = none running or unknown).
    Q_PROPERTY(double progressFraction READ progressFraction NOTIFY frameApplied)
    /// The last rest state's drape coefficient [%] (drapemeter shapes; NaN before the first rest).
    Q_PROPERTY(double drapeCoefficient READ drapeCoefficient NOTIFY resultsReady)
    Q_PROPERTY(int nodeCount READ nodeCount NOTIFY resultsReady) ///< folds at rest (drapemeter), -1 before
    Q_PROPERTY(bool hasResults READ hasResults NOTIFY resultsReady)

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
    double progressFraction() const { return m_progressFraction; }
    double drapeCoefficient() const;
    int nodeCount() const;
    bool hasResults() const { return m_results != nullptr; }

    // ---- the fabric, the body, the garment (C++) -----------------------------------
    /// Drapes this typed preset (e.g. one a CAD keeps in its own material list).
    /// `label` is what fabricPreset then reads (default: the preset's name).
    void setFabric(const fabric::FabricPreset& preset, const QString& label = {});
    /// A body the host already has (importers::load_mannequin, or its own mesh
    /// as a Mannequin): drawn, and the garment shapes collide with it. Null = none
    /// (bodyFile is used again). Takes effect at the next build.
    void setBody(std::shared_ptr<const importers::Mannequin> body);
    std::shared_ptr<const importers::Mannequin> body() const;
    /// A garment mesh (positions [m] world frame, triangles, pinned vertices);
    /// switches clothShape to GarmentMesh.
    void setGarmentMesh(const GarmentMesh& garment);
    /// Positions of the cloth as last shown [m], n x 3 (empty before the first frame).
    cloth::Positions positions() const;
    /// The last rest state (null before one): positions, solver status, the
    /// engine's drape metrics (drapemeter) and the body clearance.
    DrapeResultsPtr lastResults() const { return m_results; }

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
    /// Brings the cloth to rest with the static solver whatever the integrator,
    /// with drapeProgress(fraction, status); resultsReady and restReached follow.
    void drapeToRest();
    /// Stops a running drape or simulation where it is (running becomes false).
    void cancel();

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
    /// The cloth's positions [m] for QML (world frame, z up).
    Q_INVOKABLE QList<QVector3D> vertexPositions() const;
    /// The last rest state for QML: {vertices, outcome, newtonIterations,
    /// residual, wallSeconds, drapeCoefficientPercent, nodeCount, shadowAreaM2,
    /// meanRadiusM, hemMinZM, hemMaxZM, minBodyDistanceM, verticesInsideBody}
    /// (the drapemeter's and body's entries when they apply); empty before one.
    Q_INVOKABLE QVariantMap results() const;

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
    void onResults(const DrapeResultsPtr& results);
    void showBody(const std::shared_ptr<const importers::Mannequin>& body);
    void applyViewPreset();
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
    std::shared_ptr<const importers::Mannequin> m_body;       ///< the host's (setBody)
    std::shared_ptr<const importers::Mannequin> m_drawnBody;  ///< the one in the scene
    std::shared_ptr<const GarmentMesh> m_garment;
    DrapeResultsPtr m_results;
    double m_progressFraction = -1;

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
