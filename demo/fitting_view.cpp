#include "demo/fitting_view.hpp"

#include "widget/scene.hpp"
#include "widget/world_frame.hpp"

#include <numbers>

namespace drape::demo {

namespace {
const QString kBody = QStringLiteral("body");
const QString kTable = QStringLiteral("table");
const QString kCloth = QStringLiteral("cloth");
} // namespace

FittingView::FittingView(QWidget* parent) : widget::SceneWidget(nullptr, parent)
{
    widget::Scene* s = scene();
    s->setAntialiasing(true);
    s->camera().fovY = 30.0 * std::numbers::pi / 180.0;
    // A 6 m floor at z = 0 (#Rectangle: 100 units in its xy plane, turned to face up).
    widget::SceneItem* floor = s->addShape(QStringLiteral("floor"), QStringLiteral("#Rectangle"), QVector3D(),
                                           QVector3D(0.06f, 0.06f, 1.0f), QQuaternion::fromEulerAngles(-90, 0, 0));
    floor->setColor(QColor(0x3a, 0x3f, 0x47));
    floor->setMaterial(true, false, 1.0, 0.0);
    resetCamera();
    connect(&m_job, &widget::RestJob::progress, this, &FittingView::progress);
    connect(&m_job, &widget::RestJob::finished, this, [this](bool ok, const QString& message) {
        scene()->setStatusText(message);
        emit finished(ok, message);
    });
}

FittingView::~FittingView() = default;

widget::OrbitCamera& FittingView::camera()
{
    return scene()->camera();
}

void FittingView::setMannequin(std::shared_ptr<const importers::Mannequin> m)
{
    m_mannequin = std::move(m);
    if (m_mannequin) {
        widget::SceneItem* body = scene()->addMesh(kBody, m_mannequin->mesh.X, m_mannequin->mesh.F);
        body->setColor(QColor(0xd9, 0xc7, 0xb8));
        body->setMaterial(true, true, 0.8, 0.15);
    } else {
        scene()->removeItem(kBody);
    }
    showBody();
}

void FittingView::showBody()
{
    if (widget::SceneItem* body = scene()->item(kBody)) body->setVisible(!tablecloth());
}

void FittingView::setClothColor(const QColor& c)
{
    m_clothColor = c;
    if (widget::SceneItem* cloth = scene()->item(kCloth)) cloth->setColor(c);
}

void FittingView::resetCamera()
{
    widget::OrbitCamera& cam = camera();
    if (tablecloth()) {
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
    cam.azimuth = -std::numbers::pi / 2 - 0.45;
    scene()->cameraUpdated();
}

bool FittingView::drape(importers::Garment garment, const library::FabricChoice& fabric, QString* error)
{
    if (m_job.running()) {
        if (error) *error = tr("a drape is already running");
        return false;
    }
    try {
        m_garment = std::make_unique<importers::Scene>(garment == importers::Garment::Skirt
                                                           ? importers::make_skirt_scene(m_mannequin, fabric.preset)
                                                           : importers::make_tablecloth_scene(fabric.preset));
    } catch (const std::exception& e) {
        if (error) *error = QString::fromStdString(e.what());
        return false;
    }
    m_fabricName = QString::fromStdString(fabric.name);
    widget::Scene* s = scene();
    if (tablecloth()) {
        const importers::Table& t = m_garment->table;
        // Qt Quick 3D's #Cylinder: radius 50, height 100 units, centred. Drawn
        // 1.5 % narrower and 4 mm lower than the collider: the cloth's flat
        // triangles chord across the rounded top edge, and the drawn rim would
        // otherwise show through them.
        const double r = 0.985 * t.radius, h = t.height - 0.004;
        widget::SceneItem* table = s->addShape(kTable, QStringLiteral("#Cylinder"), widget::toScene(0, 0, h / 2),
                                               QVector3D(float(r / 50), float(h / 100), float(r / 50)));
        table->setColor(QColor(0x8a, 0x6a, 0x4a));
        table->setMaterial(true, false, 0.7, 0.5);
    } else {
        s->removeItem(kTable);
    }
    showBody();
    widget::SceneMesh* cloth = s->mesh(kCloth) ? s->mesh(kCloth) : s->addMesh(kCloth);
    cloth->setColor(m_clothColor);
    s->setTitle(QStringLiteral("%1 · %2").arg(QString::fromStdString(to_string(garment)), m_fabricName));
    s->setStatusText(QString());
    resetCamera();
    return m_job.start(QStringLiteral("drape %1").arg(m_fabricName), *m_garment->system, importers::garment_rest_options(),
                       cloth);
}

cloth::Positions FittingView::lastPositions() const
{
    return m_garment && !m_job.running() ? m_garment->system->x : cloth::Positions();
}

} // namespace drape::demo
