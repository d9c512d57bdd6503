// DrapeController's designable properties (drape_properties.hpp) and the fabric
// preset. Setters follow Qt's convention: an unchanged value returns at once, a
// rejected one emits errorOccurred and changes nothing, a new one is stored, its
// ...Changed signal emitted, then the scene or the worker follows.
#include "widget/drape_controller.hpp"

#include "widget/drape_worker.hpp"

#include "engine/cloth/params.hpp"
#include "engine/core/error.hpp"
#include "engine/library/resolve.hpp"

#include <QImageReader>

#include <cmath>

namespace drape::widget {

namespace {

bool isPositive(double v)
{
    return v > 0 && std::isfinite(v);
}

} // namespace

// ---- the cloth's definition (rebuilds on the next event-loop turn) -----------------

void DrapeController::setFabricPreset(const QString& preset)
{
    if (preset == m_settings.fabricPreset) return;
    applyFabricPreset(preset);
}

bool DrapeController::applyFabricPreset(const QString& preset)
{
    fabric::FabricPreset p;
    try {
        // A file, a built-in, a fabric of the library or a starter, as every
        // --fabric of the command line (library::resolve_fabric). Presets are
        // small and a library lookup is one indexed query: reading here lets the
        // property reject a bad name at once (the previous fabric stays in use).
        if (!preset.isEmpty()) p = library::resolve_fabric(preset.toStdString(), m_settings.libraryPath.toStdString());
    } catch (const std::exception& e) {
        fail(QStringLiteral("fabric preset '%1': %2").arg(preset, QString::fromUtf8(e.what())));
        return false;
    }
    m_preset = std::move(p);
    const bool changed = preset != m_settings.fabricPreset;
    m_settings.fabricPreset = preset;
    if (changed) emit fabricPresetChanged(preset);
    emit fabricParametersChanged();
    scheduleRebuild();
    return true;
}

void DrapeController::setFabric(const fabric::FabricPreset& preset, const QString& label)
{
    try {
        preset.params.validate("fabric '" + preset.name + "'");
    } catch (const std::exception& e) {
        return fail(QString::fromUtf8(e.what()));
    }
    m_preset = preset;
    const QString name = label.isEmpty() ? QString::fromStdString(preset.name) : label;
    if (name != m_settings.fabricPreset) {
        m_settings.fabricPreset = name;
        emit fabricPresetChanged(name);
    }
    emit fabricParametersChanged();
    scheduleRebuild();
}

void DrapeController::setLibraryPath(const QString& path)
{
    if (path == m_settings.libraryPath) return;
    m_settings.libraryPath = path;
    emit libraryPathChanged(path);
}

void DrapeController::setBodyFile(const QString& path)
{
    if (path == m_settings.bodyFile) return;
    m_settings.bodyFile = path; // imported on the worker at the next build; a bad file emits errorOccurred then
    emit bodyFileChanged(path);
    if (!isDrapemeter(m_settings.clothShape)) scheduleRebuild();
}

void DrapeController::setBody(std::shared_ptr<const importers::Mannequin> body)
{
    m_body = std::move(body);
    if (!isDrapemeter(m_settings.clothShape)) scheduleRebuild();
}

std::shared_ptr<const importers::Mannequin> DrapeController::body() const
{
    return m_mesh ? m_mesh->body : nullptr;
}

void DrapeController::setGarmentFile(const QString& path)
{
    if (path == m_settings.garmentFile) return;
    m_settings.garmentFile = path;
    emit garmentFileChanged(path);
    if (m_settings.clothShape == Drape::GarmentMesh) scheduleRebuild();
}

void DrapeController::setGarmentMesh(const GarmentMesh& garment)
{
    if (garment.X.rows() == 0 || garment.F.rows() == 0)
        return fail(QStringLiteral("garment mesh: %1 vertices, %2 triangles: nothing to drape")
                        .arg(garment.X.rows())
                        .arg(garment.F.rows()));
    m_garment = std::make_shared<const GarmentMesh>(garment);
    if (m_settings.clothShape != Drape::GarmentMesh) {
        m_settings.clothShape = Drape::GarmentMesh;
        emit clothShapeChanged(m_settings.clothShape);
    }
    scheduleRebuild();
}

void DrapeController::setSampleDiameter(double mm)
{
    if (mm == m_settings.sampleDiameter) return;
    if (!isPositive(mm)) return fail(QStringLiteral("sampleDiameter: %1 mm is not a positive length").arg(mm));
    m_settings.sampleDiameter = mm;
    emit sampleDiameterChanged(mm);
    scheduleRebuild();
}

void DrapeController::setDiscDiameter(double mm)
{
    if (mm == m_settings.discDiameter) return;
    if (!isPositive(mm)) return fail(QStringLiteral("discDiameter: %1 mm is not a positive length").arg(mm));
    m_settings.discDiameter = mm;
    emit discDiameterChanged(mm);
    scheduleRebuild();
}

void DrapeController::setGridSize(int n)
{
    if (n == m_settings.gridSize) return;
    if (n < 5 || n > 1000) return fail(QStringLiteral("gridSize: %1 nodes across is outside [5, 1000]").arg(n));
    m_settings.gridSize = n;
    emit gridSizeChanged(n);
    scheduleRebuild();
}

void DrapeController::setClothShape(Drape::ClothShape shape)
{
    if (shape == m_settings.clothShape) return;
    if (toString(shape).isEmpty()) return fail(QStringLiteral("clothShape: %1 is not a shape").arg(int(shape)));
    m_settings.clothShape = shape;
    emit clothShapeChanged(shape);
    scheduleRebuild();
}

// ---- the solver (sent to the worker) -------------------------------------------

void DrapeController::setIntegrator(Drape::Integrator integrator)
{
    if (integrator == m_settings.integrator) return;
    if (toString(integrator).isEmpty()) return fail(QStringLiteral("integrator: %1 is not an integrator").arg(int(integrator)));
    const cloth::Integrator integ = toEngine(integrator);
    m_settings.integrator = integrator;
    emit integratorChanged(integrator);
    toWorker([w = m_worker, integ] { w->setIntegrator(integ); });
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

void DrapeController::setTimeStep(double dt)
{
    if (dt == m_settings.timeStep) return;
    if (!(dt >= 0) || !std::isfinite(dt) || dt > 1.0)
        return fail(QStringLiteral("timeStep: %1 s is outside [0, 1] (0 = automatic)").arg(dt));
    m_settings.timeStep = dt;
    emit timeStepChanged(dt);
    toWorker([w = m_worker, dt] { w->setTimeStep(dt); });
}

void DrapeController::setRestSpeed(double v)
{
    if (v == m_settings.restSpeed) return;
    if (!isPositive(v)) return fail(QStringLiteral("restSpeed: %1 m/s must be positive").arg(v));
    m_settings.restSpeed = v;
    emit restSpeedChanged(v);
    toWorker([w = m_worker, s = m_settings.restSpeed, r = m_settings.restResidual] { w->setRestCriteria(s, r); });
}

void DrapeController::setRestResidual(double r)
{
    if (r == m_settings.restResidual) return;
    if (!isPositive(r)) return fail(QStringLiteral("restResidual: %1 must be positive").arg(r));
    m_settings.restResidual = r;
    emit restResidualChanged(r);
    toWorker([w = m_worker, s = m_settings.restSpeed, rr = m_settings.restResidual] { w->setRestCriteria(s, rr); });
}

// ---- what is drawn (the scene follows) -------------------------------------------

void DrapeController::setTexture(const QString& path)
{
    if (path == m_settings.texture) return;
    if (!path.isEmpty()) {
        QImageReader reader(path);
        reader.setAutoTransform(true);
        const QImage img = reader.read();
        if (img.isNull()) // keep the previous texture and property value
            return fail(QStringLiteral("texture '%1': %2").arg(path, reader.errorString()));
        // Texture coordinate v grows along the weft (+y, image up in the top view).
        m_cloth->setTextureImage(img);
    } else {
        m_cloth->clearTexture();
    }
    m_settings.texture = path;
    emit textureChanged(path);
}

bool DrapeController::setTextureImage(const QImage& image)
{
    if (image.isNull()) {
        fail(QStringLiteral("texture: the image is empty"));
        return false;
    }
    m_cloth->setTextureImage(image);
    m_settings.texture.clear(); // an in-memory image has no path
    emit textureChanged(m_settings.texture);
    return true;
}

void DrapeController::setViewPreset(Drape::ViewPreset view)
{
    if (view == m_settings.viewPreset) return;
    if (toString(view).isEmpty()) return fail(QStringLiteral("viewPreset: %1 is not a view").arg(int(view)));
    m_settings.viewPreset = view;
    emit viewPresetChanged(view);
    applyViewPreset();
}

void DrapeController::setClothColor(const QColor& c)
{
    if (c == m_settings.clothColor) return;
    m_settings.clothColor = c;
    emit clothColorChanged(c);
    m_cloth->setColor(c);
}

void DrapeController::setBackgroundColor(const QColor& c)
{
    if (c == m_settings.backgroundColor) return;
    m_settings.backgroundColor = c;
    emit backgroundColorChanged(c);
    m_scene->setBackgroundColor(c);
}

void DrapeController::setShowColliders(bool on)
{
    if (on == m_settings.showColliders) return;
    m_settings.showColliders = on;
    emit showCollidersChanged(on);
    updateVisibility();
}

void DrapeController::setShowOutlines(bool on)
{
    if (on == m_settings.showOutlines) return;
    m_settings.showOutlines = on;
    emit showOutlinesChanged(on);
    updateVisibility();
    toWorker([w = m_worker, on] { w->setOutlineWanted(on); });
    if (!on) m_simOutline->clearPolygon();
}

void DrapeController::setPickEnabled(bool on)
{
    if (on == m_settings.pickEnabled) return;
    m_settings.pickEnabled = on;
    emit pickEnabledChanged(on);
}

void DrapeController::setLabFloor(bool on)
{
    if (on == m_settings.labFloor) return;
    m_settings.labFloor = on;
    emit labFloorChanged(on);
    updateVisibility();
}

// ---- the fabric preset's parameters ------------------------------------------------

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
    auto text = [](std::string_view s) { return QString::fromUtf8(s.data(), qsizetype(s.size())); };
    for (const cloth::ParamSpec& s : cloth::param_table())
        out.push_back(QVariantMap{{QStringLiteral("key"), text(s.key)},
                                  {QStringLiteral("unit"), text(s.unit)},
                                  {QStringLiteral("doc"), text(s.doc)},
                                  {QStringLiteral("value"), shown[s.id]},
                                  {QStringLiteral("lower"), s.lower},
                                  {QStringLiteral("upper"), s.upper},
                                  {QStringLiteral("defaultValue"), s.default_value},
                                  {QStringLiteral("logScale"), s.log_scale},
                                  {QStringLiteral("editable"), editable}});
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

} // namespace drape::widget
