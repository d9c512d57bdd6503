#include "widget/rest_job.hpp"

#include "widget/frame_packer.hpp"
#include "widget/scene_item.hpp"

#include "engine/cloth/system.hpp"

#include <QElapsedTimer>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace drape::widget {

namespace {
constexpr qint64 kRestFrameIntervalMs = 300; // a static solve moves in steps: a few frames a second show it
} // namespace

QString describeSolve(const cloth::SolverStatus& st)
{
    return QStringLiteral("%1 after %2 Newton iterations, residual %3, %4 s")
        .arg(QString::fromStdString(cloth::to_string(st.outcome)))
        .arg(st.newton_iterations)
        .arg(st.residual, 0, 'g', 3)
        .arg(st.wall_seconds, 0, 'f', 1);
}

RestJob::RestJob(QObject* parent) : QObject(parent)
{
    connect(&m_job, &LongJob::progress, this, &RestJob::progress);
    connect(&m_job, &LongJob::finished, this, [this](bool ok, const QString& message) {
        if (m_mesh && m_system) m_mesh->updatePositions(m_system->x);
        emit finished(ok, ok ? describeSolve(m_status) : message);
    });
}

RestJob::~RestJob() = default; // m_job cancels and waits

bool RestJob::start(const QString& name, cloth::ClothSystem& system, cloth::RestOptions options, SceneMesh* mesh)
{
    if (m_job.running()) return false;
    m_system = &system;
    m_mesh = mesh;
    m_status = {};
    const int gen = ++m_generation;
    const cloth::ClothMesh& cm = system.mesh();
    std::vector<float> tex = texcoordsFromMaterial(cm.uv, cm.vertex_count());
    if (mesh) {
        mesh->setTopology(cm.F, cm.vertex_count(), tex);
        mesh->updatePositions(system.x);
    }
    QPointer<RestJob> self(this);
    return m_job.start(name, [this, self, sys = &system, options, gen, F = cm.F, tex](JobContext& ctx) mutable {
        options.cancel = ctx.cancelFlag();
        QElapsedTimer since;
        since.start();
        double r0 = -1;
        const double target = options.residual;
        options.progress = [&](const cloth::SolverStatus& st) {
            if (r0 < 0 && st.residual > 0) r0 = st.residual;
            double frac = -1;
            if (r0 > target && st.residual > 0)
                frac = std::clamp(std::log(r0 / st.residual) / std::log(r0 / target), 0.0, 1.0);
            ctx.report(frac, QStringLiteral("Newton iteration %1, residual %2").arg(st.newton_iterations).arg(st.residual, 0, 'g', 3));
            if (since.elapsed() > kRestFrameIntervalMs) {
                since.restart();
                PackedVertices frame = packVertices(sys->x, F, tex);
                QMetaObject::invokeMethod(
                    self.data(),
                    [self, gen, frame = std::move(frame)] {
                        if (self && self->m_generation == gen && self->m_mesh) self->m_mesh->setVertices(frame);
                    },
                    Qt::QueuedConnection);
            }
            return !ctx.cancelled();
        };
        m_status = cloth::run_to_rest(*sys, options);
        if (m_status.outcome == cloth::SolverStatus::Outcome::Cancelled) throw std::runtime_error("cancelled");
        if (m_status.outcome == cloth::SolverStatus::Outcome::Diverged)
            throw std::runtime_error("the solver diverged: " + m_status.message);
        ctx.report(1.0, describeSolve(m_status));
    });
}

} // namespace drape::widget
