#pragma once
// The simulation worker. Lives on its own QThread; owns the ClothSystem and the
// integrator. The controller talks to it only through queued calls (commands)
// and the thread-safe requestCancel() / frameConsumed(); the worker talks back
// with signals carrying immutable copies (DrapeMeshPtr, DrapeFramePtr), so the
// GUI thread never waits for a time step.
#include "widget/drape_frame.hpp"
#include "widget/drape_setup.hpp"

#include "engine/cloth/solver.hpp"

#include <QElapsedTimer>
#include <QObject>
#include <QString>

#include <atomic>
#include <memory>
#include <vector>

class QTimer;

namespace drape::widget {

class DrapeWorker : public QObject {
    Q_OBJECT
public:
    DrapeWorker();
    ~DrapeWorker() override;

    // ---- commands: call on the worker thread (queued) ----------------------
    void rebuild(std::shared_ptr<const DrapeSpec> spec);
    /// Brings the cloth to rest with the static solver (whatever the integrator),
    /// reporting a progress fraction; results follow (resultsReady).
    void drapeToRest();
    void setIntegrator(cloth::Integrator integ);
    void setTimeStep(double dt);                   ///< [s], 0 = automatic
    void setRestCriteria(double speed, double residual); ///< [m/s], relative residual [-]
    void play();
    void pause();
    void stepOnce();
    void reset();
    void setPinned(int vertex, bool pinned);
    void clearPins();
    void setMass(int vertex, double kg);
    void addSphere(SphereSpec s);
    void clearExtraColliders();
    void setOutlineWanted(bool on);
    void saveResults(const QString& jsonPath, const QString& integratorName);

    // ---- thread-safe --------------------------------------------------------
    /// Stops a running static solve at its next progress check.
    void requestCancel() { m_cancel = true; }
    /// The GUI took the last frame; the worker may send the next one.
    void frameConsumed() { m_uiReady = true; }

signals:
    void meshReady(drape::widget::DrapeMeshPtr mesh);
    void frameReady(drape::widget::DrapeFramePtr frame);
    void runningChanged(bool running);
    void restReached(double simTime, double residual);
    void resultsReady(drape::widget::DrapeResultsPtr results);
    void errorOccurred(const QString& message);
    void resultsSaved(const QString& jsonPath, const QString& objPath);

private:
    void advance();
    void runStatic(long maxNewton);
    /// Positions still as built (no step, pin, mass or collider change since)?
    bool pristine() const { return !m_touched; }
    void publish(bool force, double fraction = -1, const QString& status = {});
    void computeResults(const cloth::SolverStatus& status);
    std::shared_ptr<const importers::Mannequin> bodyFor(const DrapeSpec& spec);
    void setRunning(bool on);
    double effectiveTimeStep();
    void makeStepper();
    void fail(const QString& what, const std::exception& e);
    void emitMesh();
    bool remakeStepper(); ///< makeStepper, reporting a failure as errorOccurred

    std::unique_ptr<cloth::ClothSystem> m_sys;
    std::unique_ptr<cloth::Stepper> m_stepper;
    std::shared_ptr<const DrapeSpec> m_spec;
    std::shared_ptr<const importers::Mannequin> m_body; ///< in use
    /// Imported files kept while their path is asked for (a rebuild with a new fabric keeps the body).
    QString m_bodyPath, m_garmentPath;
    std::shared_ptr<const importers::Mannequin> m_bodyLoaded;
    std::shared_ptr<const GarmentMesh> m_garmentLoaded;
    bool m_touched = false;
    std::vector<std::shared_ptr<const cloth::Collider>> m_baseColliders;
    DrapeMeshPtr m_mesh;
    cloth::Positions m_x0;
    std::vector<float> m_texcoord;
    int m_generation = 0;
    cloth::Integrator m_integ = cloth::Integrator::ImplicitEuler;
    double m_dt = 0;
    double m_restSpeed = 1e-3;
    double m_restResidual = 1e-3;
    long m_steps = 0;
    bool m_running = false;
    bool m_outline = false;
    QTimer* m_timer = nullptr;
    QElapsedTimer m_sincePublish;
    QElapsedTimer m_sinceOutline;
    cloth::Polygon2 m_lastOutline;
    std::atomic<bool> m_cancel{false};
    std::atomic<bool> m_uiReady{true};
};

} // namespace drape::widget
