// DrapeController: the worker thread, the scene it fills and the commands.
// The designable properties' setters and the fabric preset are in
// drape_controller_settings.cpp.
#include "widget/drape_controller.hpp"

#include "widget/drape_worker.hpp"
#include "widget/picking.hpp"

#include "engine/cloth/blas_threads.hpp"
#include "engine/cloth/params.hpp"

#include <QTimer>

#include <algorithm>
#include <cmath>
#include <limits>

namespace drape::widget {

namespace {
constexpr double kOutlineHeight = 1e-3; // [m] outlines drawn just above the pedestal top, over the cloth
} // namespace

DrapeController::DrapeController(QObject* parent) : QObject(parent)
{
    cloth::portable_blas_kernel(); // on the GUI thread, before this controller's worker thread

    qRegisterMetaType<DrapeMeshPtr>();
    qRegisterMetaType<DrapeFramePtr>();
    qRegisterMetaType<DrapeResultsPtr>();

    m_scene = new Scene(this);
    m_scene->setBackgroundColor(m_settings.backgroundColor);
    m_scene->camera().setPreset(OrbitCamera::Preset::Iso);
    connect(m_scene, &Scene::cameraChanged, this, &DrapeController::cameraChanged);
    connect(m_scene, &Scene::cameraMoved, this, [this] {
        if (m_settings.viewPreset == Drape::Free) return;
        m_settings.viewPreset = Drape::Free;
        emit viewPresetChanged(m_settings.viewPreset);
    });
    connect(m_scene, &Scene::clicked, this, [this](double x, double y, double w, double h) {
        if (m_settings.pickEnabled) togglePinAt(x, y, w, h);
    });

    m_cloth = m_scene->addMesh(QStringLiteral("cloth"));
    m_cloth->setColor(m_settings.clothColor);
    m_floorBoards = new FloorBoardsGeometry();
    SceneItem* boards = m_scene->addGeometry(QStringLiteral("floorBoards"), m_floorBoards);
    boards->setColor(QColor(0x1e, 0x1e, 0x1e));
    boards->setMaterial(true, false, 0.95, 0.05);
    m_simOutline = new LineGeometry();
    m_measOutline = new LineGeometry();
    for (auto [name, geometry, color] : {std::tuple{"simulatedOutline", m_simOutline, QColor(0xff, 0x8c, 0x00)},
                                         std::tuple{"measuredOutline", m_measOutline, QColor(0x20, 0xa0, 0xff)}}) {
        SceneItem* line = m_scene->addGeometry(QString::fromLatin1(name), geometry);
        line->setColor(color);
        line->setMaterial(false, true, 0.9, 0.1);
    }
    updateVisibility();

    m_worker = new DrapeWorker();
    m_worker->moveToThread(&m_thread);
    connect(&m_thread, &QThread::finished, m_worker, &QObject::deleteLater);
    connect(m_worker, &DrapeWorker::meshReady, this, &DrapeController::onMesh);
    connect(m_worker, &DrapeWorker::frameReady, this, &DrapeController::onFrame);
    connect(m_worker, &DrapeWorker::runningChanged, this, &DrapeController::onWorkerRunning);
    connect(m_worker, &DrapeWorker::restReached, this, [this](double, double) { emit restReached(); });
    connect(m_worker, &DrapeWorker::errorOccurred, this, &DrapeController::fail);
    connect(m_worker, &DrapeWorker::resultsSaved, this, &DrapeController::resultsSaved);
    connect(m_worker, &DrapeWorker::resultsReady, this, &DrapeController::onResults);
    m_thread.setObjectName(QStringLiteral("drape-sim"));
    m_thread.start();
    toWorker([w = m_worker, integ = toEngine(m_settings.integrator)] { w->setIntegrator(integ); });
    toWorker([w = m_worker, s = m_settings.restSpeed, r = m_settings.restResidual] { w->setRestCriteria(s, r); });

    connect(&m_job, &LongJob::started, this, [this](const QString& n) {
        emit jobStarted(n);
        emit jobRunningChanged();
    });
    connect(&m_job, &LongJob::progress, this, &DrapeController::jobProgress);
    connect(&m_job, &LongJob::finished, this, [this](bool ok, const QString& msg) {
        if (!ok && msg != QLatin1String("cancelled")) emit errorOccurred(QStringLiteral("%1: %2").arg(m_job.name(), msg));
        emit jobFinished(ok, msg);
        emit jobRunningChanged();
    });

    scheduleRebuild(); // the default cloth appears on the first event-loop turn
}

DrapeController::~DrapeController()
{
    m_worker->requestCancel();
    m_thread.quit();
    m_thread.wait();
}

QObject* DrapeController::workerObject() const
{
    return m_worker;
}

void DrapeController::fail(const QString& message)
{
    emit errorOccurred(message);
}

int DrapeController::vertexCount() const
{
    return m_mesh ? m_mesh->vertexCount : 0;
}

double DrapeController::simulatedTime() const
{
    return m_frame ? m_frame->simTime : 0.0;
}

QString DrapeController::statusText() const
{
    if (!m_mesh || !m_frame) return QStringLiteral("no cloth");
    if (!m_frame->status.isEmpty()) return QStringLiteral("%1 | %2").arg(m_mesh->description, m_frame->status);
    return QStringLiteral("%1 | t = %2 s, %3 steps, max speed %4 m/s%5")
        .arg(m_mesh->description)
        .arg(m_frame->simTime, 0, 'f', 3)
        .arg(m_frame->steps)
        .arg(m_frame->maxSpeed, 0, 'g', 3)
        .arg(m_pinned.isEmpty() ? QString() : QStringLiteral(", %1 pinned").arg(m_pinned.size()));
}

// ---- building and frames -------------------------------------------------------

void DrapeController::scheduleRebuild()
{
    if (m_rebuildPending) return;
    m_rebuildPending = true;
    // Coalesce: a .ui file or QML sets several properties in a row.
    QTimer::singleShot(0, this, &DrapeController::rebuildNow);
}

void DrapeController::createCloth()
{
    m_rebuildPending = true;
    rebuildNow();
}

void DrapeController::rebuildNow()
{
    if (!m_rebuildPending) return;
    m_rebuildPending = false;
    auto spec = std::make_shared<DrapeSpec>();
    spec->preset = m_preset;
    spec->presetName = m_settings.fabricPreset;
    spec->shape = m_settings.clothShape;
    spec->body = m_body;
    spec->bodyFile = m_settings.bodyFile;
    spec->garment = m_garment;
    spec->garmentFile = m_settings.garmentFile;
    spec->setup.sample_diameter = m_settings.sampleDiameter * 1e-3;
    spec->setup.disc_diameter = m_settings.discDiameter * 1e-3;
    spec->setup.grid = m_settings.gridSize;
    spec->setup = m_preset.laid(spec->setup); // as `drape simulate` lays it (a fitted preset: as its lab did)
    m_worker->requestCancel(); // a running static solve gives way to the rebuild
    toWorker([w = m_worker, spec = std::shared_ptr<const DrapeSpec>(spec)] { w->rebuild(spec); });
    if (m_settings.running) toWorker([w = m_worker] { w->play(); });
}

void DrapeController::onMesh(const DrapeMeshPtr& mesh)
{
    m_mesh = mesh;
    m_frame.reset();
    m_cloth->setTopology(mesh->F, mesh->vertexCount, mesh->texcoord); // drawn again with the next frame
    m_pinned.clear(); // a new system starts with the pins it was built with (garments)
    for (int i : mesh->pinnedAtStart) m_pinned.insert(i);
    m_results.reset();
    showBody(mesh->body);
    showColliders(mesh->colliders);
    applyViewPreset();
    emit meshChanged();
    updatePinnedPositions();
}

void DrapeController::showColliders(const std::vector<ColliderShape>& shapes)
{
    for (const QString& name : std::as_const(m_colliderItems)) m_scene->removeItem(name);
    m_colliderItems.clear();
    QVariantList list;
    bool hasFloor = false;
    for (const ColliderShape& c : shapes) {
        const bool plane = c.kind == QLatin1String("plane");
        // Only a horizontal floor gets the lab's boards.
        if (plane && c.normal.y() > 0.99f) {
            m_floorBoards->setFloorHeight(double(c.position.y()));
            hasFloor = true;
        }
        const QQuaternion rotation = plane ? QQuaternion::rotationTo(QVector3D(0, 0, 1), c.normal) : QQuaternion();
        // The lab's stand: white floor sheet, neutral grey pedestal.
        const QColor color = plane ? QColor(0xe6, 0xe6, 0xe2)
                             : c.kind == QLatin1String("pedestal") ? QColor(0x80, 0x80, 0x80)
                                                                   : QColor(0x6a, 0x8c, 0xb0);
        const QString name = QStringLiteral("collider-%1-%2").arg(c.kind).arg(m_colliderItems.size());
        SceneItem* item = m_scene->addShape(name, c.source, c.position, c.scale, rotation);
        item->setColor(color);
        item->setMaterial(true, true, 0.95, 0.05);
        m_colliderItems << name;
        list.push_back(QVariantMap{{QStringLiteral("kind"), c.kind},
                                   {QStringLiteral("source"), c.source},
                                   {QStringLiteral("position"), c.position},
                                   {QStringLiteral("scale"), c.scale},
                                   {QStringLiteral("rotation"), rotation},
                                   {QStringLiteral("color"), color}});
    }
    m_colliders = list;
    m_hasFloor = hasFloor;
    updateVisibility();
    emit collidersChanged();
}

void DrapeController::updateVisibility()
{
    for (const QString& name : std::as_const(m_colliderItems))
        if (SceneItem* item = m_scene->item(name)) item->setVisible(m_settings.showColliders);
    const bool drapemeter = !m_mesh || isDrapemeter(m_mesh->shape);
    m_scene->item(QStringLiteral("floorBoards"))->setVisible(m_settings.showColliders && m_settings.labFloor && m_hasFloor && drapemeter);
    if (SceneItem* body = m_scene->item(QStringLiteral("body"))) body->setVisible(m_settings.showColliders);
    m_scene->item(QStringLiteral("simulatedOutline"))->setVisible(m_settings.showOutlines);
    m_scene->item(QStringLiteral("measuredOutline"))->setVisible(m_settings.showOutlines);
}

void DrapeController::onFrame(const DrapeFramePtr& frame)
{
    if (!frame || !m_mesh || frame->generation != m_mesh->generation) {
        m_worker->frameConsumed();
        return; // a frame of a cloth that has been replaced
    }
    m_frame = frame;
    m_cloth->setVertices(frame->vertices);
    m_progressFraction = frame->fraction;
    if (m_settings.showOutlines && !frame->outline.empty()) m_simOutline->setPolygon(frame->outline, kOutlineHeight);
    updatePinnedPositions(); // and the status line
    m_worker->frameConsumed();
    emit progress(frame->simTime, frame->maxSpeed);
    if (frame->fraction >= 0 || !frame->status.isEmpty()) emit drapeProgress(frame->fraction, frame->status);
    emit frameApplied();
}

void DrapeController::updatePinnedPositions()
{
    QVariantList list;
    std::vector<Eigen::Vector3d> points;
    if (m_frame) {
        for (int i : pinnedVertices())
            if (i >= 0 && i < m_frame->x.rows()) {
                points.emplace_back(m_frame->x.row(i).transpose());
                list.push_back(toScene(m_frame->x(i, 0), m_frame->x(i, 1), m_frame->x(i, 2)));
            }
    }
    m_scene->setMarkers(points, 0.004, QColor(0xff, 0xd0, 0x00));
    m_scene->setStatusText(statusText());
    if (list == m_pinnedPositions) return;
    m_pinnedPositions = list;
    emit pinnedChanged();
}

void DrapeController::onWorkerRunning(bool on)
{
    if (on == m_settings.running) return;
    m_settings.running = on;
    emit runningChanged(on);
}

// ---- commands ----------------------------------------------------------------

void DrapeController::play()
{
    setRunning(true);
}

void DrapeController::pause()
{
    setRunning(false);
}

void DrapeController::step()
{
    if (m_settings.running) setRunning(false);
    toWorker([w = m_worker] { w->stepOnce(); });
}

void DrapeController::reset()
{
    m_worker->requestCancel();
    toWorker([w = m_worker] { w->reset(); });
}

void DrapeController::clearPins()
{
    m_pinned.clear();
    toWorker([w = m_worker] { w->clearPins(); });
    updatePinnedPositions();
}

void DrapeController::clearExtraColliders()
{
    toWorker([w = m_worker] { w->clearExtraColliders(); });
}

int DrapeController::pickVertex(double x, double y, double w, double h) const
{
    if (!m_frame || !m_mesh) return -1;
    return widget::pickVertex(m_scene->camera(), m_frame->x, m_mesh->F, x, y, w, h);
}

int DrapeController::togglePinAt(double x, double y, double w, double h)
{
    const int i = pickVertex(x, y, w, h);
    if (i >= 0) setPinned(i, !isPinned(i));
    return i;
}

void DrapeController::setPinned(int vertex, bool pinned)
{
    if (vertex < 0 || vertex >= vertexCount()) {
        fail(QStringLiteral("pin: vertex %1 is not in [0, %2)").arg(vertex).arg(vertexCount()));
        return;
    }
    if (pinned == m_pinned.contains(vertex)) return;
    if (pinned)
        m_pinned.insert(vertex);
    else
        m_pinned.remove(vertex);
    toWorker([w = m_worker, vertex, pinned] { w->setPinned(vertex, pinned); });
    updatePinnedPositions();
}

QList<int> DrapeController::pinnedVertices() const
{
    QList<int> v(m_pinned.begin(), m_pinned.end());
    std::sort(v.begin(), v.end());
    return v;
}

QList<int> DrapeController::simulatedPinnedVertices() const
{
    QList<int> v;
    if (m_frame)
        for (int i : m_frame->pinned) v.push_back(i);
    return v;
}

void DrapeController::setVertexMass(int vertex, double kg)
{
    if (vertex < 0 || vertex >= vertexCount()) {
        fail(QStringLiteral("vertex mass: vertex %1 is not in [0, %2)").arg(vertex).arg(vertexCount()));
        return;
    }
    if (!(kg > 0) || !std::isfinite(kg)) {
        fail(QStringLiteral("vertex mass: %1 kg for vertex %2 is not a positive mass").arg(kg).arg(vertex));
        return;
    }
    toWorker([w = m_worker, vertex, kg] { w->setMass(vertex, kg); });
}

double DrapeController::vertexMass(int vertex) const
{
    if (!m_frame || !m_frame->mass || vertex < 0 || vertex >= m_frame->mass->size())
        return std::numeric_limits<double>::quiet_NaN();
    return (*m_frame->mass)(vertex);
}

QPointF DrapeController::projectToView(const QVector3D& worldMetres, double w, double h) const
{
    return m_scene->projectToView(Eigen::Vector3d(worldMetres.x(), worldMetres.y(), worldMetres.z()), w, h);
}

void DrapeController::addSphereCollider(const QVector3D& centreMetres, double radiusMetres)
{
    if (!(radiusMetres > 0) || !std::isfinite(radiusMetres)) {
        fail(QStringLiteral("sphere collider: radius %1 m must be positive").arg(radiusMetres));
        return;
    }
    SphereSpec s{Eigen::Vector3d(centreMetres.x(), centreMetres.y(), centreMetres.z()), radiusMetres};
    toWorker([w = m_worker, s] { w->addSphere(s); });
}

void DrapeController::saveResults(const QString& jsonPath)
{
    toWorker([w = m_worker, jsonPath, integ = toString(m_settings.integrator)] { w->saveResults(jsonPath, integ); });
}

// ---- bodies, garments, rest, results ------------------------------------------------

void DrapeController::showBody(const std::shared_ptr<const importers::Mannequin>& body)
{
    if (body == m_drawnBody) return;
    m_drawnBody = body;
    if (!body) {
        m_scene->removeItem(QStringLiteral("body"));
        return;
    }
    SceneItem* item = m_scene->addMesh(QStringLiteral("body"), body->mesh.X, body->mesh.F);
    item->setColor(QColor(0xd9, 0xc7, 0xb8));
    item->setMaterial(true, true, 0.8, 0.15);
    item->setVisible(m_settings.showColliders);
}

void DrapeController::applyViewPreset()
{
    OrbitCamera& cam = m_scene->camera();
    switch (m_settings.viewPreset) {
    case Drape::Top: cam.setPreset(OrbitCamera::Preset::Top); break;
    case Drape::Side: cam.setPreset(OrbitCamera::Preset::Side); break;
    case Drape::Iso: cam.setPreset(OrbitCamera::Preset::Iso); break;
    case Drape::Close: cam.setPreset(OrbitCamera::Preset::Close); break;
    case Drape::Free: return; // where the user left it
    }
    if (m_mesh && !isDrapemeter(m_mesh->shape)) {
        // The lab's stations look at the pedestal: a garment is framed from the
        // same direction, at a distance that shows it and its body whole.
        const Eigen::Vector3d lo = m_mesh->boundsMin, hi = m_mesh->boundsMax;
        cam.target = 0.5 * (lo + hi);
        const double radius = 0.5 * (hi - lo).norm();
        cam.distance = std::clamp(1.1 * radius / std::sin(0.5 * cam.fovY), 0.05, 50.0);
    }
    m_scene->cameraUpdated();
}

void DrapeController::onResults(const DrapeResultsPtr& results)
{
    if (!results || !m_mesh || results->generation != m_mesh->generation) return;
    m_results = results;
    emit resultsReady();
}

void DrapeController::drapeToRest()
{
    if (m_rebuildPending) rebuildNow();
    m_worker->requestCancel(); // a running static solve gives way
    toWorker([w = m_worker] { w->pause(); });
    toWorker([w = m_worker] { w->drapeToRest(); });
}

void DrapeController::cancel()
{
    setRunning(false);
    m_worker->requestCancel();
}

double DrapeController::drapeCoefficient() const
{
    return m_results && m_results->drape ? m_results->drape->metrics.drape_coefficient_percent
                                         : std::numeric_limits<double>::quiet_NaN();
}

int DrapeController::nodeCount() const
{
    return m_results && m_results->drape ? m_results->drape->metrics.node_count : -1;
}

cloth::Positions DrapeController::positions() const
{
    return m_frame ? m_frame->x : cloth::Positions();
}

QList<QVector3D> DrapeController::vertexPositions() const
{
    QList<QVector3D> out;
    if (!m_frame) return out;
    out.reserve(m_frame->x.rows());
    for (Eigen::Index i = 0; i < m_frame->x.rows(); ++i)
        out.push_back(QVector3D(float(m_frame->x(i, 0)), float(m_frame->x(i, 1)), float(m_frame->x(i, 2))));
    return out;
}

QVariantMap DrapeController::results() const
{
    QVariantMap m;
    if (!m_results) return m;
    const DrapeResults& r = *m_results;
    m[QStringLiteral("vertices")] = int(r.x.rows());
    m[QStringLiteral("outcome")] = QString::fromStdString(cloth::to_string(r.status.outcome));
    m[QStringLiteral("newtonIterations")] = qlonglong(r.status.newton_iterations);
    m[QStringLiteral("residual")] = r.status.residual;
    m[QStringLiteral("wallSeconds")] = r.status.wall_seconds;
    if (r.x.rows() > 0) {
        m[QStringLiteral("minZM")] = r.x.col(2).minCoeff();
        m[QStringLiteral("maxZM")] = r.x.col(2).maxCoeff();
    }
    if (r.drape) {
        const cloth::DrapeMetrics& d = r.drape->metrics;
        m[QStringLiteral("drapeCoefficientPercent")] = d.drape_coefficient_percent;
        m[QStringLiteral("nodeCount")] = d.node_count;
        m[QStringLiteral("shadowAreaM2")] = d.shadow_area_m2;
        m[QStringLiteral("meanRadiusM")] = d.mean_radius_m;
        m[QStringLiteral("hemMinZM")] = r.drape->hem.min_z;
        m[QStringLiteral("hemMaxZM")] = r.drape->hem.max_z;
    }
    if (r.penetration) {
        m[QStringLiteral("minBodyDistanceM")] = r.penetration->min_distance;
        m[QStringLiteral("verticesInsideBody")] = r.penetration->inside;
    }
    return m;
}

void DrapeController::showMeasuredOutline(const QPolygonF& outlineMetres)
{
    cloth::Polygon2 poly;
    poly.reserve(std::size_t(outlineMetres.size()));
    for (const QPointF& p : outlineMetres) poly.emplace_back(p.x(), p.y());
    if (poly.size() < 3) {
        fail(QStringLiteral("measured outline: %1 points are not a polygon").arg(poly.size()));
        return;
    }
    m_measOutline->setPolygon(poly, kOutlineHeight);
    setShowOutlines(true);
}

void DrapeController::setMeasuredOutline(const QVariantList& points)
{
    QPolygonF poly;
    for (const QVariant& v : points) poly.push_back(v.toPointF());
    showMeasuredOutline(poly);
}

void DrapeController::clearMeasuredOutline()
{
    m_measOutline->clearPolygon();
}

bool DrapeController::startJob(const QString& name, JobFunction fn)
{
    if (!m_job.start(name, std::move(fn))) {
        fail(QStringLiteral("%1: another job (%2) is running").arg(name, m_job.name()));
        return false;
    }
    return true;
}

void DrapeController::cancelJob()
{
    m_job.cancel();
}

} // namespace drape::widget
