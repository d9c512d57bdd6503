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
#include "widget/drape_controller.hpp"

#include <QImage>
#include <QWidget>

class QQuickWidget;

namespace drape::widget {

class DrapeView : public QWidget {
    Q_OBJECT
    Q_PROPERTY(QString fabricPreset READ fabricPreset WRITE setFabricPreset NOTIFY fabricPresetChanged)
    Q_PROPERTY(double sampleDiameter READ sampleDiameter WRITE setSampleDiameter NOTIFY sampleDiameterChanged)
    Q_PROPERTY(double discDiameter READ discDiameter WRITE setDiscDiameter NOTIFY discDiameterChanged)
    Q_PROPERTY(int gridSize READ gridSize WRITE setGridSize NOTIFY gridSizeChanged)
    Q_PROPERTY(QString clothShape READ clothShape WRITE setClothShape NOTIFY clothShapeChanged)
    Q_PROPERTY(QString integrator READ integrator WRITE setIntegrator NOTIFY integratorChanged)
    Q_PROPERTY(QString texture READ texture WRITE setTexture NOTIFY textureChanged)
    Q_PROPERTY(bool running READ running WRITE setRunning NOTIFY runningChanged)
    Q_PROPERTY(double timeStep READ timeStep WRITE setTimeStep NOTIFY timeStepChanged)
    Q_PROPERTY(double restSpeed READ restSpeed WRITE setRestSpeed NOTIFY restSpeedChanged)
    Q_PROPERTY(double restResidual READ restResidual WRITE setRestResidual NOTIFY restResidualChanged)
    Q_PROPERTY(QString viewPreset READ viewPreset WRITE setViewPreset NOTIFY viewPresetChanged)
    Q_PROPERTY(QColor clothColor READ clothColor WRITE setClothColor NOTIFY clothColorChanged)
    Q_PROPERTY(QColor backgroundColor READ backgroundColor WRITE setBackgroundColor NOTIFY backgroundColorChanged)
    Q_PROPERTY(bool showColliders READ showColliders WRITE setShowColliders NOTIFY showCollidersChanged)
    Q_PROPERTY(bool showOutlines READ showOutlines WRITE setShowOutlines NOTIFY showOutlinesChanged)
    Q_PROPERTY(bool pickEnabled READ pickEnabled WRITE setPickEnabled NOTIFY pickEnabledChanged)
    Q_PROPERTY(bool labFloor READ labFloor WRITE setLabFloor NOTIFY labFloorChanged)

public:
    explicit DrapeView(QWidget* parent = nullptr);
    ~DrapeView() override;

    DrapeController* controller() const { return m_controller; }
    QQuickWidget* quickWidget() const { return m_quick; }
    /// The rendered view as an image (renders now; for screenshots and tests).
    QImage grabFrame();

    QSize sizeHint() const override { return {480, 360}; }
    QSize minimumSizeHint() const override { return {120, 90}; }

    QString fabricPreset() const { return m_controller->fabricPreset(); }
    void setFabricPreset(const QString& v) { m_controller->setFabricPreset(v); }
    double sampleDiameter() const { return m_controller->sampleDiameter(); }
    void setSampleDiameter(double mm) { m_controller->setSampleDiameter(mm); }
    double discDiameter() const { return m_controller->discDiameter(); }
    void setDiscDiameter(double mm) { m_controller->setDiscDiameter(mm); }
    int gridSize() const { return m_controller->gridSize(); }
    void setGridSize(int n) { m_controller->setGridSize(n); }
    QString clothShape() const { return m_controller->clothShape(); }
    void setClothShape(const QString& v) { m_controller->setClothShape(v); }
    QString integrator() const { return m_controller->integrator(); }
    void setIntegrator(const QString& v) { m_controller->setIntegrator(v); }
    QString texture() const { return m_controller->texture(); }
    void setTexture(const QString& v) { m_controller->setTexture(v); }
    bool running() const { return m_controller->running(); }
    void setRunning(bool on) { m_controller->setRunning(on); }
    double timeStep() const { return m_controller->timeStep(); }
    void setTimeStep(double dt) { m_controller->setTimeStep(dt); }
    double restSpeed() const { return m_controller->restSpeed(); }
    void setRestSpeed(double v) { m_controller->setRestSpeed(v); }
    double restResidual() const { return m_controller->restResidual(); }
    void setRestResidual(double r) { m_controller->setRestResidual(r); }
    QString viewPreset() const { return m_controller->viewPreset(); }
    void setViewPreset(const QString& v) { m_controller->setViewPreset(v); }
    QColor clothColor() const { return m_controller->clothColor(); }
    void setClothColor(const QColor& c) { m_controller->setClothColor(c); }
    QColor backgroundColor() const { return m_controller->backgroundColor(); }
    void setBackgroundColor(const QColor& c) { m_controller->setBackgroundColor(c); }
    bool showColliders() const { return m_controller->showColliders(); }
    void setShowColliders(bool on) { m_controller->setShowColliders(on); }
    bool showOutlines() const { return m_controller->showOutlines(); }
    void setShowOutlines(bool on) { m_controller->setShowOutlines(on); }
    bool pickEnabled() const { return m_controller->pickEnabled(); }
    void setPickEnabled(bool on) { m_controller->setPickEnabled(on); }
    bool labFloor() const { return m_controller->labFloor(); }
    void setLabFloor(bool on) { m_controller->setLabFloor(on); }

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
    void fabricPresetChanged(const QString& preset);
    void sampleDiameterChanged(double mm);
    void discDiameterChanged(double mm);
    void gridSizeChanged(int n);
    void clothShapeChanged(const QString& shape);
    void integratorChanged(const QString& name);
    void textureChanged(const QString& path);
    void runningChanged(bool running);
    void timeStepChanged(double dt);
    void restSpeedChanged(double v);
    void restResidualChanged(double r);
    void viewPresetChanged(const QString& name);
    void clothColorChanged(const QColor& c);
    void backgroundColorChanged(const QColor& c);
    void showCollidersChanged(bool on);
    void showOutlinesChanged(bool on);
    void pickEnabledChanged(bool on);
    void labFloorChanged(bool on);
    void progress(double simulatedTime, double maxSpeed);
    void restReached();
    void errorOccurred(const QString& message);
    void resultsSaved(const QString& jsonPath, const QString& objPath);
    void jobProgress(double fraction, const QString& message);
    void jobFinished(bool ok, const QString& message);

private:
    DrapeController* m_controller = nullptr;
    QQuickWidget* m_quick = nullptr;
};

} // namespace drape::widget
