#pragma once
// DrapeView: the embeddable drape widget. A QWidget hosting a QQuickWidget with
// the Qt Quick 3D scene (DrapeScene.qml); the engine runs on a worker thread
// (see DrapeController), so the host's UI never waits for the simulation.
//
// Mouse: left-drag orbits, right/middle-drag (or shift+left) pans, the wheel
// zooms, a left click (no drag) pins the vertex under the cursor or unpins it.
//
// Units: sampleDiameter and discDiameter in millimetres; timeStep [s];
// restSpeed [m/s]; restResidual is relative to the cloth's weight.
//
// Its designable properties and signals are the controller's, generated from
// one list (drape_properties.hpp) and forwarded.
#include "widget/drape_controller.hpp"
#include "widget/drape_properties.hpp"

#include <QImage>
#include <QWidget>

class QQuickWidget;

namespace drape::widget {

class DrapeView : public QWidget {
    Q_OBJECT
    DRAPE_VIEW_PROPERTIES(DRAPE_DECLARE_Q_PROPERTY)

public:
    explicit DrapeView(QWidget* parent = nullptr);
    ~DrapeView() override;

    DrapeController* controller() const { return m_controller; }
    QQuickWidget* quickWidget() const { return m_quick; }
    /// The rendered view as an image (renders now; for screenshots and tests).
    QImage grabFrame();

    QSize sizeHint() const override { return {480, 360}; }
    QSize minimumSizeHint() const override { return {120, 90}; }

#define DRAPE_VIEW_FORWARD(Type, Arg, name, setter, init)    \
    Type name() const { return m_controller->name(); }       \
    void setter(Arg value) { m_controller->setter(value); }
    DRAPE_VIEW_PROPERTIES(DRAPE_VIEW_FORWARD)
#undef DRAPE_VIEW_FORWARD

public slots:
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
    QQuickWidget* m_quick = nullptr;
};

} // namespace drape::widget
