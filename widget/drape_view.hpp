#pragma once
// DrapeView: the embeddable drape widget (the drapemeter, a garment on a body,
// a tablecloth; fabrics by name from the library). A QWidget showing its controller's
// Scene (a SceneWidget: qml/SceneView.qml in a QQuickWidget); the engine runs on
// a worker thread (see DrapeController), so the host's UI never waits for the
// simulation. Its designable properties and signals are the controller's,
// generated from one list (drape_properties.hpp) and forwarded.
//
// Mouse: left-drag orbits, right/middle-drag (or shift+left) pans, the wheel
// zooms, a left click (no drag) pins the vertex under the cursor or unpins it.
//
// Units: sampleDiameter and discDiameter in millimetres; timeStep [s];
// restSpeed [m/s]; restResidual is relative to the cloth's weight.
#include "widget/drape_widget_export.hpp"
#include "widget/drape_controller.hpp"
#include "widget/drape_properties.hpp"
#include "widget/scene_widget.hpp"

#include <QImage>
#include <QWidget>

class QQuickWidget;

namespace drape::widget {

class DRAPE_WIDGET_EXPORT DrapeView : public QWidget {
    Q_OBJECT
    DRAPE_VIEW_PROPERTIES(DRAPE_DECLARE_Q_PROPERTY)

public:
    explicit DrapeView(QWidget* parent = nullptr);
    ~DrapeView() override;

    DrapeController* controller() const { return m_controller; }
    SceneWidget* sceneWidget() const { return m_view; }
    QQuickWidget* quickWidget() const { return m_view->quickWidget(); }
    /// The rendered view as an image (renders now; for screenshots and tests).
    QImage grabFrame() { return m_view->grabFrame(); }

    QSize sizeHint() const override { return {480, 360}; }
    QSize minimumSizeHint() const override { return {120, 90}; }

#define DRAPE_VIEW_FORWARD(Type, Arg, name, setter, init)    \
    Type name() const { return m_controller->name(); }       \
    void setter(Arg value) { m_controller->setter(value); }
    DRAPE_VIEW_PROPERTIES(DRAPE_VIEW_FORWARD)
#undef DRAPE_VIEW_FORWARD

    // ---- the embedding API (the controller's; see DrapeController) ----------------
    void setFabric(const fabric::FabricPreset& preset, const QString& label = {}) { m_controller->setFabric(preset, label); }
    void setBody(std::shared_ptr<const importers::Mannequin> body) { m_controller->setBody(std::move(body)); }
    void setGarmentMesh(const GarmentMesh& garment) { m_controller->setGarmentMesh(garment); }
    cloth::Positions positions() const { return m_controller->positions(); }
    DrapeResultsPtr lastResults() const { return m_controller->lastResults(); }
    double drapeCoefficient() const { return m_controller->drapeCoefficient(); } ///< [%], NaN before a drapemeter rest

public slots:
    void drapeToRest() { m_controller->drapeToRest(); }
    void cancel() { m_controller->cancel(); }
    void play() { m_controller->play(); }
    void pause() { m_controller->pause(); }
    void step() { m_controller->step(); }
    void reset() { m_controller->reset(); }
    void createCloth() { m_controller->createCloth(); }
    void saveResults(const QString& jsonPath) { m_controller->saveResults(jsonPath); }
    bool loadFabricPreset(const QString& path) { return m_controller->loadFabricPreset(path); }
    bool saveFabricPreset(const QString& path) { return m_controller->saveFabricPreset(path); }
    void showMeasuredOutline(const QPolygonF& outlineMetres) { m_controller->showMeasuredOutline(outlineMetres); }
    void cancelJob() { m_controller->cancelJob(); }

signals:
    DRAPE_VIEW_PROPERTIES(DRAPE_DECLARE_CHANGED_SIGNAL)
    DRAPE_VIEW_SIGNALS(DRAPE_DECLARE_SIGNAL)

private:
    DrapeController* m_controller = nullptr;
    SceneWidget* m_view = nullptr;
};

} // namespace drape::widget
