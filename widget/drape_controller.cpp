#include "widget/drape_controller.hpp"

#include "widget/cloth_geometry.hpp"
#include "widget/drape_worker.hpp"
#include "widget/line_geometry.hpp"

#include "engine/core/error.hpp"
#include "engine/cloth/params.hpp"
#include "engine/fabric/seed_format.hpp"

#include <Eigen/Geometry>

#include <QImageReader>
#include <QQuick3DTextureData>
#include <QTimer>

#include <cmath>
#include <limits>
#include <variant>

namespace drape::widget {

namespace {
constexpr double kOutlineHeight = 1e-3; // [m] outlines drawn just above the pedestal top, over the cloth
} // namespace

DrapeController::DrapeController(QObject* parent) : QObject(parent)
{
    qRegisterMetaType<DrapeMeshPtr>();
    qRegisterMetaType<DrapeFramePtr>();

    m_cloth = new ClothGeometry();
    m_cloth->QObject::setParent(this);
    m_simOutline = new LineGeometry();
    m_simOutline->QObject::setParent(this);
    m_measOutline = new LineGeometry();
    m_measOutline->QObject::setParent(this);
    m_textureData = new QQuick3DTextureData();
    m_textureData->QObject::setParent(this);
    m_floorBoards = new FloorBoardsGeometry();
    m_floorBoards->QObject::setParent(this);
    m_camera.setPreset(OrbitCamera::Preset::Iso);

    m_worker = new DrapeWorker();
    m_worker->moveToThread(&m_thread);
    connect(&m_thread, &QThread::finished, m_worker, &QObject::deleteLater);
    connect(m_worker, &DrapeWorker::meshReady, this, &DrapeController::onMesh);
    connect(m_worker, &DrapeWorker::frameReady, this, &DrapeController::onFrame);
    connect(m_worker, &DrapeWorker::runningChanged, this, &DrapeController::onWorkerRunning);
    connect(m_worker, &DrapeWorker::restReached, this, [this](double, double) { emit restReached(); });
    connect(m_worker, &DrapeWorker::errorOccurred, this, &DrapeController::fail);
    connect(m_worker, &DrapeWorker::resultsSaved, this, &DrapeController::resultsSaved);
    m_thread.setObjectName(QStringLiteral("drape-sim"));
    m_thread.start();
    toWorker([w = m_worker, integ = cloth::parse_integrator(m_settings.integrator.toStdString())] { w->setIntegrator(integ); });
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

template <class F>
void DrapeController::toWorker(F&& f)
{
    QMetaObject::invokeMethod(m_worker, std::forward<F>(f), Qt::QueuedConnection);
}

void DrapeController::fail(const QString& message)
{
    emit errorOccurred(message);
}

// ---- properties ------------------------------------------------------------

void DrapeController::setFabricPreset(const QString& preset)
{
    if (preset == m_settings.fabricPreset) return;
    applyFabricPreset(preset);
}

bool DrapeController::applyFabricPreset(const QString& preset)
{
    fabric::FabricPreset p;
    try {
        // Presets are small JSON files: reading them here lets the property
        // reject a bad file at once (the previous fabric stays in use).
        if (!preset.isEmpty()) p = fabric::load_fabric(preset.toStdString());
    } catch (const std::exception& e) {
        fail(QStringLiteral("fabric preset '%1': %2").arg(preset, QString::fromUtf8(e.what())));
        return false;
    }
    m_preset = std::move(p);
    const bool changed = preset != m_settings.fabricPreset;
    m_settings.fabricPreset = preset;
    if (changed) emit fabricPresetChanged(m_settings.fabricPreset);
    emit fabricParametersChanged();
    scheduleRebuild();
    return true;
}

void DrapeController::setSampleDiameter(double mm)
{
    if (mm == m_settings.sampleDiameter) return;
    if (!(mm > 0) || !std::isfinite(mm)) {
        fail(QStringLiteral("sampleDiameter: %1 mm is not a positive length").arg(mm));
        return;
    }
    m_settings.sampleDiameter = mm;
    emit sampleDiameterChanged(mm);
    scheduleRebuild();
}

void DrapeController::setDiscDiameter(double mm)
{
    if (mm == m_settings.discDiameter) return;
    if (!(mm > 0) || !std::isfinite(mm)) {
        fail(QStringLiteral("discDiameter: %1 mm is not a positive length").arg(mm));
        return;
    }
    m_settings.discDiameter = mm;
    emit discDiameterChanged(mm);
    scheduleRebuild();
}

void DrapeController::setGridSize(int n)
{
    if (n == m_settings.gridSize) return;
    if (n < 5 || n > 1000) {
        fail(QStringLiteral("gridSize: %1 nodes across is outside [5, 1000]").arg(n));
        return;
    }
    m_settings.gridSize = n;
    emit gridSizeChanged(n);
    scheduleRebuild();
}

void DrapeController::setClothShape(const QString& shape)
{
    if (shape == m_settings.clothShape) return;
    if (shape != QLatin1String("disc") && shape != QLatin1String("square")) {
        fail(QStringLiteral("clothShape: '%1' is not a shape (use disc or square)").arg(shape));
        return;
    }
    m_settings.clothShape = shape;
    emit clothShapeChanged(shape);
    scheduleRebuild();
}

void DrapeController::setIntegrator(const QString& name)
{
    if (name == m_settings.integrator) return;
    cloth::Integrator integ;
    try {
        integ = cloth::parse_integrator(name.toStdString());
    } catch (const std::exception& e) {
        fail(QStringLiteral("integrator '%1': %2").arg(name, QString::fromUtf8(e.what())));
        return;
    }
    m_settings.integrator = name;
    emit integratorChanged(name);
    toWorker([w = m_worker, integ] { w->setIntegrator(integ); });
}

void DrapeController::setTexture(const QString& path)
{
    if (path == m_settings.texture) return;
    if (!path.isEmpty()) {
        QImageReader reader(path);
        reader.setAutoTransform(true);
        const QImage img = reader.read();
        if (img.isNull()) {
            fail(QStringLiteral("texture '%1': %2").arg(path, reader.errorString()));
            return; // keep the previous texture and property value
        }
        uploadTexture(img);
        m_hasTexture = true;
    } else {
        m_hasTexture = false;
    }
    m_settings.texture = path;
    emit textureChanged(m_settings.texture);
}

bool DrapeController::setTextureImage(const QImage& image)
{
    if (image.isNull()) {
        fail(QStringLiteral("texture: the image is empty"));
        return false;
    }
    uploadTexture(image);
    m_hasTexture = true;
    m_settings.texture.clear(); // an in-memory image has no path
    emit textureChanged(m_settings.texture);
    return true;
}

void DrapeController::uploadTexture(const QImage& image)
{
    // Texture coordinate v grows along the weft (+y, image up in the top view),
    // while image rows run downwards: mirror so the image is upright seen from above.
    const QImage rgba = image.convertToFormat(QImage::Format_RGBA8888).mirrored(false, true);
    m_textureData->setSize(rgba.size());
    m_textureData->setFormat(QQuick3DTextureData::RGBA8);
    m_textureData->setHasTransparency(false);
    m_textureData->setTextureData(QByteArray(reinterpret_cast<const char*>(rgba.constBits()), rgba.sizeInBytes()));
}

void DrapeController::setRunning(bool on)
{
    if (on == m_settings.running) return;
    m_settings.running = on;
    emit runningChanged(on);
    if (on) {
        if (!m_rebuildPending) toWorker([w = m_worker] { w->play(); }); // else rebuildNow() plays
    } else {
        m_worker->requestCancel(); // a static solve stops at its next check
        toWorker([w = m_worker] { w->pause(); });
    }
}

void DrapeController::onWorkerRunning(bool on)
{
    if (on == m_settings.running) return;
    m_settings.running = on;
    emit runningChanged(on);
}

void DrapeController::setTimeStep(double dt)
{
    if (dt == m_settings.timeStep) return;
    if (!(dt >= 0) || !std::isfinite(dt) || dt > 1.0) {
        fail(QStringLiteral("timeStep: %1 s is outside [0, 1] (0 = automatic)").arg(dt));
        return;
    }
    m_settings.timeStep = dt;
    emit timeStepChanged(dt);
    toWorker([w = m_worker, dt] { w->setTimeStep(dt); });
}

void DrapeController::setRestSpeed(double v)
{
    if (v == m_settings.restSpeed) return;
    if (!(v > 0) || !std::isfinite(v)) {
        fail(QStringLiteral("restSpeed: %1 m/s must be positive").arg(v));
        return;
    }
    m_settings.restSpeed = v;
    emit restSpeedChanged(v);
    toWorker([w = m_worker, s = m_settings.restSpeed, r = m_settings.restResidual] { w->setRestCriteria(s, r); });
}

void DrapeController::setRestResidual(double r)
{
    if (r == m_settings.restResidual) return;
    if (!(r > 0) || !std::isfinite(r)) {
        fail(QStringLiteral("restResidual: %1 must be positive").arg(r));
        return;
    }
    m_settings.restResidual = r;
    emit restResidualChanged(r);
    toWorker([w = m_worker, s = m_settings.restSpeed, rr = m_settings.restResidual] { w->setRestCriteria(s, rr); });
}

void DrapeController::setViewPreset(const QString& name)
{
    if (name == m_settings.viewPreset) return;
    if (name == QLatin1String("top"))
        m_camera.setPreset(OrbitCamera::Preset::Top);
    else if (name == QLatin1String("side"))
        m_camera.setPreset(OrbitCamera::Preset::Side);
    else if (name == QLatin1String("iso"))
        m_camera.setPreset(OrbitCamera::Preset::Iso);
    else if (name == QLatin1String("close"))
        m_camera.setPreset(OrbitCamera::Preset::Close);
    else if (name != QLatin1String("free")) {
        fail(QStringLiteral("viewPreset: '%1' is not a view (use top, side, iso, close or free)").arg(name));
        return;
    }
    m_settings.viewPreset = name;
    emit viewPresetChanged(name);
    emit cameraChanged();
}

void DrapeController::setClothColor(const QColor& c)
{
    if (c == m_settings.clothColor) return;
    m_settings.clothColor = c;
    emit clothColorChanged(c);
}

void DrapeController::setBackgroundColor(const QColor& c)
{
    if (c == m_settings.backgroundColor) return;
    m_settings.backgroundColor = c;
    emit backgroundColorChanged(c);
}

void DrapeController::setShowColliders(bool on)
{
    if (on == m_settings.showColliders) return;
    m_settings.showColliders = on;
    emit showCollidersChanged(on);
}

void DrapeController::setShowOutlines(bool on)
{
    if (on == m_settings.showOutlines) return;
    m_settings.showOutlines = on;
    emit showOutlinesChanged(on);
    toWorker([w = m_worker, on] { w->setOutlineWanted(on); });
    if (!on) m_simOutline->clearPolygon();
}

void DrapeController::setLabFloor(bool on)
{
    if (on == m_settings.labFloor) return;
    m_settings.labFloor = on;
    emit labFloorChanged(on);
}

void DrapeController::setPickEnabled(bool on)
{
    if (on == m_settings.pickEnabled) return;
    m_settings.pickEnabled = on;
    emit pickEnabledChanged(on);
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
    spec->setup.sample_diameter = m_settings.sampleDiameter * 1e-3;
    spec->setup.disc_diameter = m_settings.discDiameter * 1e-3;
    spec->setup.grid = m_settings.gridSize;
    m_worker->requestCancel(); // a running static solve gives way to the rebuild
    toWorker([w = m_worker, spec = std::shared_ptr<const DrapeSpec>(spec)] { w->rebuild(spec); });
    if (m_settings.running) toWorker([w = m_worker] { w->play(); });
}

void DrapeController::onMesh(const DrapeMeshPtr& mesh)
{
    m_mesh = mesh;
    m_frame.reset();
    m_cloth->setMesh(mesh);
    m_pinned.clear(); // a new system starts without pins
    m_colliderShapes = mesh->colliders;
    rebuildColliderList();
    emit meshChanged();
    updatePinnedPositions();
}

void DrapeController::rebuildColliderList()
{
    QVariantList list;
    bool hasFloor = false;
    for (const ColliderShape& c : m_colliderShapes) {
        QVariantMap m;
        const bool plane = c.kind == QLatin1String("plane");
        // Only a horizontal floor gets the lab's boards.
        const bool boards = plane && c.normal.y() > 0.99f;
        if (boards) {
            m_floorBoards->setFloorHeight(double(c.position.y()));
            hasFloor = true;
        }
        m[QStringLiteral("kind")] = c.kind;
        m[QStringLiteral("source")] = c.source;
        m[QStringLiteral("position")] = c.position;
        m[QStringLiteral("scale")] = c.scale;
        m[QStringLiteral("rotation")] = plane ? QQuaternion::rotationTo(QVector3D(0, 0, 1), c.normal) : QQuaternion();
        // The lab's stand: white floor sheet, neutral grey pedestal.
        m[QStringLiteral("color")] = plane ? QColor(0xe6, 0xe6, 0xe2)
                                     : c.kind == QLatin1String("pedestal") ? QColor(0x80, 0x80, 0x80)
                                                                           : QColor(0x6a, 0x8c, 0xb0);
        list.push_back(m);
    }
    m_colliders = list;
    if (hasFloor != m_hasFloor) {
        m_hasFloor = hasFloor;
        emit labFloorChanged(m_settings.labFloor);
    }
    emit collidersChanged();
}

void DrapeController::onFrame(const DrapeFramePtr& frame)
{
    if (!frame || !m_mesh || frame->generation != m_mesh->generation) {
        m_worker->frameConsumed();
        return; // a frame of a cloth that has been replaced
    }
    m_frame = frame;
    m_cloth->setFrame(frame);
    if (m_settings.showOutlines && !frame->outline.empty()) m_simOutline->setPolygon(frame->outline, kOutlineHeight);
    updatePinnedPositions();
    m_worker->frameConsumed();
    emit progress(frame->simTime, frame->maxSpeed);
    emit frameApplied();
}

void DrapeController::updatePinnedPositions()
{
    QVariantList list;
    if (m_frame) {
        QList<int> sorted(m_pinned.begin(), m_pinned.end());
        std::sort(sorted.begin(), sorted.end());
        for (int i : sorted)
            if (i >= 0 && i < m_frame->x.rows()) list.push_back(toScene(m_frame->x(i, 0), m_frame->x(i, 1), m_frame->x(i, 2)));
    }
    if (list == m_pinnedPositions) return;
    m_pinnedPositions = list;
    emit pinnedChanged();
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

void DrapeController::orbit(double dxPixels, double dyPixels)
{
    m_camera.orbit(-dxPixels * 0.01, dyPixels * 0.01); // [rad per pixel]
    if (m_settings.viewPreset != QLatin1String("free")) {
        m_settings.viewPreset = QStringLiteral("free");
        emit viewPresetChanged(m_settings.viewPreset);
    }
    emit cameraChanged();
}

void DrapeController::pan(double dxPixels, double dyPixels, double viewHeight)
{
    if (!(viewHeight > 0)) return;
    m_camera.pan(dxPixels / viewHeight, dyPixels / viewHeight);
    if (m_settings.viewPreset != QLatin1String("free")) {
        m_settings.viewPreset = QStringLiteral("free");
        emit viewPresetChanged(m_settings.viewPreset);
    }
    emit cameraChanged();
}

void DrapeController::zoom(double wheelDelta)
{
    m_camera.zoom(std::pow(0.999, wheelDelta)); // one notch (120) = 11 % closer
    emit cameraChanged();
}

int DrapeController::pickVertex(double x, double y, double w, double h) const
{
    if (!m_frame || !m_mesh || w <= 0 || h <= 0) return -1;
    Eigen::Vector3d o, d;
    m_camera.ray(x, y, w, h, o, d);
    const cloth::Positions& X = m_frame->x;
    const cloth::Triangles& F = m_mesh->F;
    double best = std::numeric_limits<double>::infinity();
    Eigen::Index bestT = -1;
    // Moller-Trumbore against every triangle: a 10,000-vertex cloth takes well
    // under a millisecond, and both faces count (the cloth is double-sided).
    for (Eigen::Index t = 0; t < F.rows(); ++t) {
        const Eigen::Vector3d a = X.row(F(t, 0)), b = X.row(F(t, 1)), c = X.row(F(t, 2));
        const Eigen::Vector3d e1 = b - a, e2 = c - a, p = d.cross(e2);
        const double det = e1.dot(p);
        if (std::abs(det) < 1e-18) continue;
        const double inv = 1.0 / det;
        const Eigen::Vector3d s = o - a;
        const double u = s.dot(p) * inv;
        if (u < 0 || u > 1) continue;
        const Eigen::Vector3d q = s.cross(e1);
        const double v = d.dot(q) * inv;
        if (v < 0 || u + v > 1) continue;
        const double dist = e2.dot(q) * inv;
        if (dist > 0 && dist < best) {
            best = dist;
            bestT = t;
        }
    }
    if (bestT < 0) return -1;
    const Eigen::Vector3d hit = o + best * d;
    int vertex = -1;
    double nearest = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 3; ++k) {
        const int i = F(bestT, k);
        const double r = (X.row(i).transpose() - hit).squaredNorm();
        if (r < nearest) {
            nearest = r;
            vertex = i;
        }
    }
    return vertex;
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
    double px = 0, py = 0;
    if (!m_camera.project(Eigen::Vector3d(worldMetres.x(), worldMetres.y(), worldMetres.z()), w, h, px, py))
        return {std::nan(""), std::nan("")};
    return {px, py};
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
    toWorker([w = m_worker, jsonPath, integ = m_settings.integrator] { w->saveResults(jsonPath, integ); });
}

bool DrapeController::saveFabricPreset(const QString& path)
{
    try {
        if (path.isEmpty()) throw FileError("save fabric preset: empty file name");
        fabric::save_fabric(m_preset, path.toStdString());
    } catch (const std::exception& e) {
        fail(QStringLiteral("save fabric preset '%1': %2").arg(path, QString::fromUtf8(e.what())));
        return false;
    }
    return true;
}

QVariantList DrapeController::fabricParameters() const
{
    QVariantList out;
    // A seed preset shows its continuum equivalents, read-only (its grid constants are the physics).
    const bool editable = !m_preset.is_seed();
    const cloth::FabricParams& shown = m_preset.params;
    for (const cloth::ParamSpec& s : cloth::param_table()) {
        QVariantMap m;
        m[QStringLiteral("key")] = QString::fromUtf8(s.key.data(), qsizetype(s.key.size()));
        m[QStringLiteral("unit")] = QString::fromUtf8(s.unit.data(), qsizetype(s.unit.size()));
        m[QStringLiteral("doc")] = QString::fromUtf8(s.doc.data(), qsizetype(s.doc.size()));
        m[QStringLiteral("value")] = shown[s.id];
        m[QStringLiteral("lower")] = s.lower;
        m[QStringLiteral("upper")] = s.upper;
        m[QStringLiteral("defaultValue")] = s.default_value;
        m[QStringLiteral("logScale")] = s.log_scale;
        m[QStringLiteral("editable")] = editable;
        out.push_back(m);
    }
    return out;
}

bool DrapeController::setFabricParameter(const QString& key, double value)
{
    const QByteArray k = key.toUtf8();
    const cloth::ParamSpec* s = cloth::find_param(std::string_view(k.constData(), std::size_t(k.size())));
    if (!s) {
        fail(QStringLiteral("fabric parameter '%1': no such parameter").arg(key));
        return false;
    }
    if (m_preset.is_seed()) {
        fail(QStringLiteral("fabric parameter '%1': the preset holds the seed's grid constants; "
                            "edit them in the preset file").arg(key));
        return false;
    }
    cloth::FabricParams edited = m_preset.params;
    edited[s->id] = value;
    try {
        edited.validate("fabric parameter");
    } catch (const std::exception& e) {
        fail(QString::fromUtf8(e.what()));
        return false;
    }
    m_preset.set_params(edited);
    emit fabricParametersChanged();
    scheduleRebuild();
    return true;
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
