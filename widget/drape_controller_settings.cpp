// DrapeController's designable properties (drape_properties.hpp) and the fabric
// preset. Setters follow Qt's convention: an unchanged value returns at once, a
// rejected one emits errorOccurred and changes nothing, a new one is stored, its
// ...Changed signal emitted, then the scene or the worker follows.
#include "widget/drape_controller.hpp"

#include "widget/drape_worker.hpp"

#include "engine/cloth/params.hpp"
#include "engine/core/error.hpp"

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
    if (changed) emit fabricPresetChanged(preset);
    emit fabricParametersChanged();
    scheduleRebuild();
    return true;
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

void DrapeController::setClothShape(const QString& shape)
{
    if (shape == m_settings.clothShape) return;
    if (shape != QLatin1String("disc") && shape != QLatin1String("square"))
        return fail(QStringLiteral("clothShape: '%1' is not a shape (use disc or square)").arg(shape));
    m_settings.clothShape = shape;
    emit clothShapeChanged(shape);
    scheduleRebuild();
}

// ---- the solver (sent to the worker) -------------------------------------------

void DrapeController::setIntegrator(const QString& name)
{
    if (name == m_settings.integrator) return;
    cloth::Integrator integ;
    try {
        integ = cloth::parse_integrator(name.toStdString());
    } catch (const std::exception& e) {
        return fail(QStringLiteral("integrator '%1': %2").arg(name, QString::fromUtf8(e.what())));
    }
    m_settings.integrator = name;
    emit integratorChanged(name);
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

void DrapeController::setViewPreset(const QString& name)
{
    if (name == m_settings.viewPreset) return;
    OrbitCamera& cam = m_scene->camera();
    if (name == QLatin1String("top"))
        cam.setPreset(OrbitCamera::Preset::Top);
    else if (name == QLatin1String("side"))
        cam.setPreset(OrbitCamera::Preset::Side);
    else if (name == QLatin1String("iso"))
        cam.setPreset(OrbitCamera::Preset::Iso);
    else if (name == QLatin1String("close"))
        cam.setPreset(OrbitCamera::Preset::Close);
    else if (name != QLatin1String("free"))
        return fail(QStringLiteral("viewPreset: '%1' is not a view (use top, side, iso, close or free)").arg(name));
    m_settings.viewPreset = name;
    emit viewPresetChanged(name);
    m_scene->cameraUpdated();
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
