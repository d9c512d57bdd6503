#include "demo/fitting_view.hpp"

#include "widget/drape_qml.hpp"

#include <Eigen/Geometry>

#include <QElapsedTimer>
#include <QPointer>
#include <QQmlContext>
#include <QQuickWidget>
#include <QVBoxLayout>

#include <cmath>

namespace drape::demo {

namespace {

widget::DrapeMeshPtr makeMesh(int generation, const cloth::Triangles& F, int n)
{
    auto m = std::make_shared<widget::DrapeMeshData>();
    m->generation = generation;
    m->vertexCount = n;
    m->F = F;
    m->indexData.resize(qsizetype(F.size()) * qsizetype(sizeof(quint32)));
    auto* idx = reinterpret_cast<quint32*>(m->indexData.data());
    for (Eigen::Index t = 0; t < F.rows(); ++t)
        for (int k = 0; k < 3; ++k) idx[3 * t + k] = quint32(F(t, k));
    return m;
}

/// Interleaved scene positions, smooth normals and texture coordinates (the layout ClothGeometry uploads).
widget::DrapeFramePtr makeFrame(int generation, const cloth::Positions& x, const cloth::Triangles& F,
                                const std::vector<float>& tex)
{
    auto f = std::make_shared<widget::DrapeFrame>();
    const int n = int(x.rows());
    f->generation = generation;
    f->x = x;
    cloth::Positions nrm = cloth::Positions::Zero(n, 3);
    for (Eigen::Index t = 0; t < F.rows(); ++t) {
        const int a = F(t, 0), b = F(t, 1), c = F(t, 2);
        const Eigen::Vector3d fa = (x.row(b) - x.row(a)).cross(x.row(c) - x.row(a));
        nrm.row(a) += fa;
        nrm.row(b) += fa;
        nrm.row(c) += fa;
    }
    f->vertexData.resize(qsizetype(n) * widget::kFloatsPerVertex * qsizetype(sizeof(float)));
    auto* out = reinterpret_cast<float*>(f->vertexData.data());
    QVector3D lo(1e9f, 1e9f, 1e9f), hi(-1e9f, -1e9f, -1e9f);
    for (int i = 0; i < n; ++i) {
        const QVector3D p = widget::toScene(x(i, 0), x(i, 1), x(i, 2));
        const double len = nrm.row(i).norm();
        const QVector3D q = len > 0 ? widget::toScene(nrm(i, 0) / len, nrm(i, 1) / len, nrm(i, 2) / len) : QVector3D(0, 1, 0);
        float* o = out + std::ptrdiff_t(i) * widget::kFloatsPerVertex;
        o[0] = p.x(); o[1] = p.y(); o[2] = p.z();
        o[3] = q.x(); o[4] = q.y(); o[5] = q.z();
        o[6] = tex.empty() ? 0.f : tex[std::size_t(2 * i)];
        o[7] = tex.empty() ? 0.f : tex[std::size_t(2 * i + 1)];
        lo = QVector3D(std::min(lo.x(), p.x()), std::min(lo.y(), p.y()), std::min(lo.z(), p.z()));
        hi = QVector3D(std::max(hi.x(), p.x()), std::max(hi.y(), p.y()), std::max(hi.z(), p.z()));
    }
    f->boundsMin = lo;
    f->boundsMax = hi;
    return f;
}

} // namespace

// ---- FittingSceneState --------------------------------------------------------

FittingSceneState::FittingSceneState(QObject* parent) : QObject(parent)
{
    m_body = new widget::ClothGeometry();
    m_cloth = new widget::ClothGeometry();
    camera.fovY = 30.0 * 3.14159265358979323846 / 180.0;
}

FittingSceneState::~FittingSceneState()
{
    delete m_body;
    delete m_cloth;
}

void FittingSceneState::orbit(double dx, double dy)
{
    // Half a turn per 400 px: the feel of DrapeView's orbit.
    camera.orbit(-dx * 3.14159265358979323846 / 400.0, dy * 3.14159265358979323846 / 400.0);
    emit cameraChanged();
}

void FittingSceneState::zoom(double wheelDelta)
{
    camera.zoom(std::pow(0.999, wheelDelta));
    emit cameraChanged();
}

// ---- FittingView ----------------------------------------------------------------

FittingView::FittingView(QWidget* parent) : QWidget(parent)
{
    widget::registerDrapeQmlTypes();
    m_state = new FittingSceneState(this);
    auto* layout = new QVBoxLayout(this);
    layout->setContentsMargins(0, 0, 0, 0);
    m_quick = new QQuickWidget(this);
    m_quick->setObjectName(QStringLiteral("fittingQuickWidget"));
    m_quick->setResizeMode(QQuickWidget::SizeRootObjectToView);
    m_quick->rootContext()->setContextProperty(QStringLiteral("fitting"), m_state);
    m_quick->setSource(QUrl(QStringLiteral("qrc:/drapedemo/qml/FittingScene.qml")));
    for (const QQmlError& e : m_quick->errors()) qWarning("FittingScene.qml: %s", qPrintable(e.toString()));
    layout->addWidget(m_quick);
    resetCamera();

    connect(&m_job, &widget::LongJob::progress, this, &FittingView::progress);
    connect(&m_job, &widget::LongJob::finished, this, [this](bool ok, const QString& message) {
        if (m_scene) showPositions(m_scene->system->x, true);
        QString text = message;
        if (ok)
            text = QStringLiteral("%1 after %2 Newton iterations, residual %3, %4 s")
                       .arg(QString::fromStdString(cloth::to_string(m_status.outcome)))
                       .arg(m_status.newton_iterations)
                       .arg(m_status.residual, 0, 'g', 3)
                       .arg(m_status.wall_seconds, 0, 'f', 1);
        m_state->m_status = text;
        emit m_state->statusChanged();
        emit finished(ok, text);
    });
}

FittingView::~FittingView()
{
    m_job.cancel();
    // The scene references the geometry objects: take it down first.
    delete m_quick;
    m_quick = nullptr;
}

void FittingView::setMannequin(std::shared_ptr<const importers::Mannequin> m)
{
    m_mannequin = std::move(m);
    showBody();
}

void FittingView::showBody()
{
    m_state->m_bodyVisible = m_mannequin && (!m_scene || m_scene->garment == importers::Garment::Skirt);
    if (m_mannequin) {
        const auto& M = m_mannequin->mesh;
        ++m_generation;
        m_state->m_body->setMesh(makeMesh(m_generation, M.F, int(M.X.rows())));
        m_state->m_body->setFrame(makeFrame(m_generation, M.X, M.F, {}));
    }
    emit m_state->sceneChanged();
}

void FittingView::setClothColor(const QColor& c)
{
    m_state->m_clothColor = c;
    emit m_state->sceneChanged();
}

void FittingView::resetCamera()
{
    auto& cam = m_state->camera;
    const bool table = m_scene && m_scene->garment == importers::Garment::Tablecloth;
    if (table) {
        cam.target = Eigen::Vector3d(0, 0, 0.45);
        cam.distance = 3.2;
        cam.elevation = 0.45;
    } else {
        const double h = m_mannequin ? m_mannequin->height() : 1.7;
        // Frame the lower body, where the skirt is.
        cam.target = Eigen::Vector3d(0, 0, 0.5 * h);
        cam.distance = 3.4 * h / 1.7;
        cam.elevation = 0.12;
    }
    // MakeHuman faces -y after the z-up conversion: look at the front, a little from the side.
    cam.azimuth = -1.5707963267948966 - 0.45;
    emit m_state->cameraChanged();
}

bool FittingView::drape(importers::Garment garment, const library::FabricChoice& fabric, QString* error)
{
    if (m_job.running()) {
        if (error) *error = tr("a drape is already running");
        return false;
    }
    try {
        auto scene = std::make_unique<importers::Scene>(garment == importers::Garment::Skirt ? importers::make_skirt_scene(m_mannequin, fabric.preset)
                                                                       : importers::make_tablecloth_scene(fabric.preset));
        m_scene = std::move(scene);
    } catch (const std::exception& e) {
        if (error) *error = QString::fromStdString(e.what());
        return false;
    }
    m_fabricName = QString::fromStdString(fabric.name);
    m_status = {};
    const cloth::ClothMesh& cm = m_scene->system->mesh();
    // Texture coordinates from the material coordinates (for a future weave texture).
    m_clothTex.assign(std::size_t(2 * cm.vertex_count()), 0.f);
    if (cm.uv.rows() == cm.vertex_count()) {
        const Eigen::Vector2d lo = cm.uv.colwise().minCoeff();
        const double span = std::max((cm.uv.colwise().maxCoeff() - cm.uv.colwise().minCoeff()).maxCoeff(), 1e-9);
        for (int i = 0; i < cm.vertex_count(); ++i) {
            m_clothTex[std::size_t(2 * i)] = float((cm.uv(i, 0) - lo.x()) / span);
            m_clothTex[std::size_t(2 * i + 1)] = float((cm.uv(i, 1) - lo.y()) / span);
        }
    }
    ++m_generation;
    m_clothGeneration = m_generation;
    m_state->m_cloth->setMesh(makeMesh(m_clothGeneration, cm.F, cm.vertex_count()));
    showPositions(m_scene->system->x, true);
    m_state->m_tableVisible = garment == importers::Garment::Tablecloth;
    if (m_state->m_tableVisible) {
        const importers::Table& t = m_scene->table;
        // Qt Quick 3D's #Cylinder: radius 50, height 100 units, centred. Drawn
        // 1.5 % narrower and 4 mm lower than the collider: the cloth's flat
        // triangles chord across the rounded top edge, and the drawn rim would
        // otherwise show through them.
        const double r = 0.985 * t.radius, h = t.height - 0.004;
        m_state->m_tablePosition = widget::toScene(0, 0, h / 2);
        m_state->m_tableScale = QVector3D(float(r / 50), float(h / 100), float(r / 50));
    }
    m_state->m_title = QStringLiteral("%1 · %2").arg(QString::fromStdString(to_string(garment)), m_fabricName);
    showBody();
    resetCamera();

    cloth::ClothSystem* sys = m_scene->system.get();
    QPointer<FittingView> self(this);
    const int gen = m_clothGeneration;
    const QString name = m_fabricName;
    return m_job.start(QStringLiteral("drape %1").arg(name), [this, self, sys, gen](widget::JobContext& ctx) {
        cloth::RestOptions opt = importers::garment_rest_options();
        opt.cancel = ctx.cancelFlag();
        QElapsedTimer since;
        since.start();
        double r0 = -1;
        const double target = opt.residual;
        opt.progress = [&](const cloth::SolverStatus& st) {
            if (r0 < 0 && st.residual > 0) r0 = st.residual;
            double frac = -1;
            if (r0 > target && st.residual > 0)
                frac = std::clamp(std::log(r0 / st.residual) / std::log(r0 / target), 0.0, 1.0);
            ctx.report(frac, QStringLiteral("Newton iteration %1, residual %2")
                                 .arg(st.newton_iterations)
                                 .arg(st.residual, 0, 'g', 3));
            if (since.elapsed() > 300) {
                since.restart();
                const cloth::Positions x = sys->x;
                QMetaObject::invokeMethod(
                    self.data(),
                    [self, x, gen]() {
                        if (self && self->m_clothGeneration == gen) self->showPositions(x, true);
                    },
                    Qt::QueuedConnection);
            }
            return !ctx.cancelled();
        };
        m_status = cloth::run_to_rest(*sys, opt);
        if (m_status.outcome == cloth::SolverStatus::Outcome::Cancelled) throw std::runtime_error("cancelled");
        if (m_status.outcome == cloth::SolverStatus::Outcome::Diverged)
            throw std::runtime_error("the solver diverged: " + m_status.message);
        ctx.report(1.0, QStringLiteral("%1 after %2 Newton iterations, residual %3, %4 s")
                            .arg(QString::fromStdString(cloth::to_string(m_status.outcome)))
                            .arg(m_status.newton_iterations)
                            .arg(m_status.residual, 0, 'g', 3)
                            .arg(m_status.wall_seconds, 0, 'f', 1));
    });
}

void FittingView::cancel()
{
    m_job.cancel();
}

cloth::Positions FittingView::lastPositions() const
{
    return m_scene && !m_job.running() ? m_scene->system->x : cloth::Positions();
}

void FittingView::showPositions(const cloth::Positions& x, bool)
{
    if (!m_scene) return;
    m_state->m_cloth->setFrame(makeFrame(m_clothGeneration, x, m_scene->system->mesh().F, m_clothTex));
}

QImage FittingView::grabFrame()
{
    return m_quick ? m_quick->grabFramebuffer() : QImage();
}

} // namespace drape::demo
