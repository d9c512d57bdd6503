#pragma once
// RestJob: brings a cloth system to rest off the GUI thread and shows it as it
// goes. cloth::run_to_rest runs in a LongJob (progress, cancel, exceptions as
// messages); a few times a second the current positions are packed on the
// job's thread and handed to a SceneMesh, so the view shows the drape forming.
// The fitting demo drapes its garments with it.
#include "widget/drape_widget_export.hpp"
#include "widget/long_job.hpp"

#include "engine/cloth/solver.hpp"

#include <QObject>
#include <QPointer>

namespace drape::widget {

class SceneMesh;

class DRAPE_WIDGET_EXPORT RestJob : public QObject {
    Q_OBJECT
public:
    explicit RestJob(QObject* parent = nullptr);
    ~RestJob() override; ///< cancels and waits for a running solve

    /// Starts solving `system` with `options` (their cancel flag and progress
    /// callback are set here) and shows it in `mesh`, whose topology becomes the
    /// system's. The caller keeps the system alive and leaves it alone until
    /// finished. False when a solve is running.
    bool start(const QString& name, cloth::ClothSystem& system, cloth::RestOptions options, SceneMesh* mesh);
    void cancel() { m_job.cancel(); }
    bool running() const { return m_job.running(); }
    /// The last solve's outcome (set when finished is emitted).
    const cloth::SolverStatus& status() const { return m_status; }

signals:
    /// fraction in [0, 1] (the residual's way down to the target, on a log scale),
    /// or negative when unknown.
    void progress(double fraction, const QString& message);
    /// ok = converged or stopped at the iteration budget without diverging.
    void finished(bool ok, const QString& message);

private:
    cloth::SolverStatus m_status; ///< written by the job's thread until it finishes
    cloth::ClothSystem* m_system = nullptr;
    QPointer<SceneMesh> m_mesh;
    int m_generation = 0;
    LongJob m_job; ///< last: destroyed (cancelled and joined) before what its thread writes
};

/// "converged after 145 Newton iterations, residual 2e-05, 62.0 s".
DRAPE_WIDGET_EXPORT QString describeSolve(const cloth::SolverStatus& status);

} // namespace drape::widget
