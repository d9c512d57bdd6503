#pragma once
// FittingView: one 3-D view of a fitting (mannequin or table, and the draped
// garment). The drape runs on a worker thread (widget's LongJob), frames come
// back as immutable copies, so the window stays live and can be cancelled.
//
// The widget library's DrapeView is built around the drapemeter (a specimen on
// a pedestal); a fitting needs an imported body and a generated garment, so
// this view reuses DrapeView's building blocks (ClothGeometry, OrbitCamera,
// LongJob, the z-up -> y-up convention) with its own small scene.
#include "engine/library/fabric_choices.hpp"
#include "importers/garment_scene.hpp"

#include "widget/cloth_geometry.hpp"
#include "widget/long_job.hpp"
#include "widget/orbit_camera.hpp"

#include <QColor>
#include <QImage>
#include <QMutex>
#include <QObject>
#include <QQuaternion>
#include <QVector3D>
#include <QWidget>

#include <memory>

class QQuickWidget;

namespace drape::demo {

/// What the QML scene binds to.
class FittingSceneState : public QObject {
    Q_OBJECT
    Q_PROPERTY(drape::widget::ClothGeometry* bodyGeometry READ bodyGeometry CONSTANT)
    Q_PROPERTY(drape::widget::ClothGeometry* clothGeometry READ clothGeometry CONSTANT)
    Q_PROPERTY(bool bodyVisible READ bodyVisible NOTIFY sceneChanged)
    Q_PROPERTY(bool tableVisible READ tableVisible NOTIFY sceneChanged)
    Q_PROPERTY(QVector3D tablePosition READ tablePosition NOTIFY sceneChanged)
    Q_PROPERTY(QVector3D tableScale READ tableScale NOTIFY sceneChanged)
    Q_PROPERTY(QColor clothColor READ clothColor NOTIFY sceneChanged)
    Q_PROPERTY(QString title READ title NOTIFY sceneChanged)
    Q_PROPERTY(QString status READ status NOTIFY statusChanged)
    Q_PROPERTY(QVector3D cameraPosition READ cameraPosition NOTIFY cameraChanged)
    Q_PROPERTY(QQuaternion cameraRotation READ cameraRotation NOTIFY cameraChanged)
    Q_PROPERTY(double fieldOfView READ fieldOfView NOTIFY cameraChanged)
public:
    explicit FittingSceneState(QObject* parent = nullptr);
    ~FittingSceneState() override;
    widget::ClothGeometry* bodyGeometry() const { return m_body; }
    widget::ClothGeometry* clothGeometry() const { return m_cloth; }
    bool bodyVisible() const { return m_bodyVisible; }
    bool tableVisible() const { return m_tableVisible; }
    QVector3D tablePosition() const { return m_tablePosition; }
    QVector3D tableScale() const { return m_tableScale; }
    QColor clothColor() const { return m_clothColor; }
    QString title() const { return m_title; }
    QString status() const { return m_status; }
    QVector3D cameraPosition() const { return camera.scenePosition(); }
    QQuaternion cameraRotation() const { return camera.sceneRotation(); }
    double fieldOfView() const { return camera.fovYDegrees(); }

    Q_INVOKABLE void orbit(double dxPixels, double dyPixels);
    Q_INVOKABLE void zoom(double wheelDelta);

    widget::OrbitCamera camera;
    widget::ClothGeometry* m_body = nullptr;
    widget::ClothGeometry* m_cloth = nullptr;
    bool m_bodyVisible = false, m_tableVisible = false;
    QVector3D m_tablePosition, m_tableScale;
    QColor m_clothColor{0xb0, 0x3a, 0x48};
    QString m_title, m_status;

signals:
    void sceneChanged();
    void statusChanged();
    void cameraChanged();
};

class FittingView : public QWidget {
    Q_OBJECT
public:
    explicit FittingView(QWidget* parent = nullptr);
    ~FittingView() override;

    /// Shows this body (null hides it). Takes effect for the next skirt drape.
    void setMannequin(std::shared_ptr<const importers::Mannequin> m);
    std::shared_ptr<const importers::Mannequin> mannequin() const { return m_mannequin; }
    /// Builds the scene on the GUI thread (fast) and drapes it on a worker
    /// thread. Returns false with `error` set when the scene cannot be built
    /// (bad fabric, no mannequin) or a drape is already running.
    bool drape(importers::Garment garment, const library::FabricChoice& fabric, QString* error = nullptr);
    void cancel();
    bool busy() const { return m_job.running(); }

    void setClothColor(const QColor& c);
    /// Frames the camera on the current scene (body or table).
    void resetCamera();
    widget::OrbitCamera& camera() { return m_state->camera; }
    void cameraChanged() { emit m_state->cameraChanged(); }

    /// Renders now and returns the image.
    QImage grabFrame();

    /// Results of the last finished drape (valid after finished(true, ...)).
    const cloth::SolverStatus& lastStatus() const { return m_status; }
    cloth::Positions lastPositions() const;
    const importers::Scene* scene() const { return m_scene.get(); }
    QString fabricName() const { return m_fabricName; }

    QSize sizeHint() const override { return {560, 640}; }

signals:
    /// fraction in [0, 1], or negative when unknown.
    void progress(double fraction, const QString& message);
    void finished(bool ok, const QString& message);

private:
    void showBody();
    void showPositions(const cloth::Positions& x, bool cloth);
    QQuickWidget* m_quick = nullptr;
    FittingSceneState* m_state = nullptr;
    std::shared_ptr<const importers::Mannequin> m_mannequin;
    std::unique_ptr<importers::Scene> m_scene;
    widget::LongJob m_job;
    cloth::SolverStatus m_status;
    QString m_fabricName;
    int m_generation = 0;
    int m_clothGeneration = -1;
    std::vector<float> m_clothTex;
};

} // namespace drape::demo
