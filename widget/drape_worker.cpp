#include "widget/drape_worker.hpp"

#include "widget/drape_results.hpp"
#include "widget/rest_job.hpp"

#include "engine/cloth/blas_threads.hpp"
#include "engine/cloth/colliders.hpp"
#include "engine/core/error.hpp"
#include "importers/garment_scene.hpp"

#include <QTimer>

#include <algorithm>
#include <cmath>

namespace drape::widget {

namespace {

// At most ~30 cloth frames per second: smooth enough to watch, and on a small
// machine with software OpenGL each rendered frame takes CPU from the solver.
constexpr qint64 kFrameIntervalMs = 30;

QString fabricName(const fabric::FabricPreset& p) { return QString::fromStdString(p.name); }

} // namespace

DrapeWorker::DrapeWorker()
{
    m_timer = new QTimer(this);
    m_timer->setSingleShot(true);
    m_timer->setInterval(0);
    connect(m_timer, &QTimer::timeout, this, &DrapeWorker::advance);
    m_sincePublish.start();
    m_sinceOutline.start();
}

DrapeWorker::~DrapeWorker()
{
    m_stepper.reset(); // holds a reference to the system
}

void DrapeWorker::fail(const QString& what, const std::exception& e)
{
    emit errorOccurred(what + QStringLiteral(": ") + QString::fromUtf8(e.what()));
}

std::shared_ptr<const importers::Mannequin> DrapeWorker::bodyFor(const DrapeSpec& spec)
{
    if (isDrapemeter(spec.shape) || spec.shape == Drape::Tablecloth) return nullptr;
    if (spec.body) return spec.body;
    QString path = spec.bodyFile;
    if (path.isEmpty() && spec.shape == Drape::Skirt) path = QString::fromStdString(importers::default_mannequin_path());
    if (path.isEmpty()) return nullptr;
    if (path != m_bodyPath || !m_bodyLoaded) {
        // Imported here, on the worker: a body of tens of thousands of triangles
        // takes a second to read and index, which the GUI never waits for.
        m_bodyLoaded = std::make_shared<const importers::Mannequin>(importers::load_mannequin(path.toStdString()));
        m_bodyPath = path;
    }
    return m_bodyLoaded;
}

void DrapeWorker::rebuild(std::shared_ptr<const DrapeSpec> spec)
{
    if (!spec) return;
    // The controller plays again after a rebuild when it is meant to be running.
    setRunning(false);
    try {
        std::shared_ptr<const importers::Mannequin> body = bodyFor(*spec);
        if (spec->shape == Drape::GarmentMesh && !spec->garment && !spec->garmentFile.isEmpty()) {
            if (spec->garmentFile != m_garmentPath || !m_garmentLoaded) {
                m_garmentLoaded = std::make_shared<const GarmentMesh>(loadGarmentMesh(spec->garmentFile.toStdString()));
                m_garmentPath = spec->garmentFile;
            }
            auto withGarment = std::make_shared<DrapeSpec>(*spec);
            withGarment->garment = m_garmentLoaded;
            spec = std::move(withGarment);
        }
        std::unique_ptr<cloth::ClothSystem> sys = makeDrapeSystem(*spec, body);
        // Swap only after everything built: a failed rebuild keeps the old cloth.
        m_stepper.reset();
        m_sys = std::move(sys);
        m_spec = std::move(spec);
        m_body = std::move(body);
        m_x0 = m_sys->x;
        m_baseColliders = m_sys->colliders();
        m_steps = 0;
        m_touched = false;
        makeStepper();
        emitMesh();
        publish(true);
    } catch (const std::exception& e) {
        fail(QStringLiteral("cannot build the cloth"), e);
    }
}

void DrapeWorker::emitMesh()
{
    auto mesh = std::make_shared<DrapeMeshData>();
    const cloth::ClothMesh& cm = m_sys->mesh();
    mesh->generation = ++m_generation;
    mesh->vertexCount = m_sys->vertex_count();
    mesh->F = cm.F;
    mesh->texcoord = texcoordsFromMaterial(cm.uv, mesh->vertexCount);
    mesh->boundary = cm.boundary;
    for (const auto& c : m_sys->colliders())
        if (c) describeColliders(*c, mesh->colliders);
    mesh->sampleRadius = 0.5 * m_spec->setup.sample_diameter;
    mesh->discRadius = 0.5 * m_spec->setup.disc_diameter;
    mesh->description = QStringLiteral("%1, %2 vertices, %3 triangles")
                            .arg(fabricName(m_spec->preset))
                            .arg(mesh->vertexCount)
                            .arg(cm.F.rows());
    mesh->shape = m_spec->shape;
    for (int i = 0; i < m_sys->vertex_count(); ++i)
        if (m_sys->pinned(i)) mesh->pinnedAtStart.push_back(i);
    mesh->body = m_body;
    mesh->boundsMin = m_sys->x.colwise().minCoeff().transpose();
    mesh->boundsMax = m_sys->x.colwise().maxCoeff().transpose();
    if (m_body) {
        mesh->boundsMin = mesh->boundsMin.cwiseMin(m_body->bounds.min);
        mesh->boundsMax = mesh->boundsMax.cwiseMax(m_body->bounds.max);
    }
    m_texcoord = mesh->texcoord;
    m_mesh = mesh;
    emit meshReady(mesh);
}

void DrapeWorker::makeStepper()
{
    m_stepper.reset();
    if (!m_sys || m_integ == cloth::Integrator::Static) return;
    m_stepper = std::make_unique<cloth::Stepper>(*m_sys, m_integ);
}

bool DrapeWorker::remakeStepper()
{
    try {
        makeStepper();
        return true;
    } catch (const std::exception& e) {
        fail(QStringLiteral("integrator"), e);
        return false;
    }
}

void DrapeWorker::setIntegrator(cloth::Integrator integ)
{
    if (integ == m_integ) return;
    const bool wasRunning = m_running;
    setRunning(false);
    m_integ = integ;
    if (remakeStepper() && wasRunning) play();
}

void DrapeWorker::setTimeStep(double dt)
{
    m_dt = dt;
}

void DrapeWorker::setRestCriteria(double speed, double residual)
{
    m_restSpeed = speed;
    m_restResidual = residual;
}

double DrapeWorker::effectiveTimeStep()
{
    if (m_dt > 0) return m_dt;
    // Automatic: explicit schemes just inside their stability limit; implicit
    // Euler two steps per displayed frame (it is stable at any step).
    if (m_integ == cloth::Integrator::ImplicitEuler) return 1.0 / 120.0;
    const double lim = m_stepper ? m_stepper->explicit_dt_limit() : 1e-4;
    return std::min(0.9 * lim, 1.0 / 240.0);
}

void DrapeWorker::setRunning(bool on)
{
    if (on == m_running) return;
    m_running = on;
    if (!on) m_timer->stop();
    emit runningChanged(on);
}

void DrapeWorker::play()
{
    if (!m_sys) return;
    m_cancel = false;
    if (m_integ == cloth::Integrator::Static) {
        runStatic(-1);
        return;
    }
    if (!m_stepper && !remakeStepper()) return;
    setRunning(true);
    m_timer->start();
}

void DrapeWorker::pause()
{
    setRunning(false);
    publish(true);
}

void DrapeWorker::advance()
{
    if (!m_running || !m_sys || !m_stepper) return;
    QElapsedTimer budget;
    budget.start();
    m_touched = true;
    const double dt = effectiveTimeStep();
    try {
        // Step for about one display frame, then let queued commands (pin, pause) in.
        do {
            if (!m_stepper->step(dt)) {
                setRunning(false);
                publish(true);
                emit errorOccurred(QStringLiteral("the simulation diverged at t = %1 s with %2 steps of %3 s "
                                                  "(integrator %4): use a smaller time step or the implicit integrator; "
                                                  "press reset to start again")
                                       .arg(m_sys->time, 0, 'g', 4)
                                       .arg(m_steps)
                                       .arg(dt, 0, 'g', 3)
                                       .arg(QString::fromStdString(cloth::to_string(m_integ))));
                return;
            }
            ++m_steps;
        } while (budget.elapsed() < 15);
        const double speed = maxFreeSpeed(*m_sys);
        if (speed < m_restSpeed) {
            // Explicit integrators step without the self-contact barrier; so does their rest test.
            const double res = cloth::relative_residual(*m_sys, m_integ == cloth::Integrator::ImplicitEuler);
            if (res < m_restResidual) {
                setRunning(false);
                publish(true);
                cloth::SolverStatus st;
                st.outcome = cloth::SolverStatus::Outcome::Converged;
                st.steps = m_steps;
                st.residual = res;
                st.sim_time = m_sys->time;
                st.max_speed = speed;
                computeResults(st);
                emit restReached(m_sys->time, res);
                return;
            }
        }
    } catch (const std::exception& e) {
        setRunning(false);
        fail(QStringLiteral("simulation step"), e);
        return;
    }
    publish(false);
    m_timer->start();
}

void DrapeWorker::drapeToRest()
{
    if (!m_sys) return;
    m_cancel = false;
    runStatic(-1);
}

void DrapeWorker::runStatic(long maxNewton)
{
    setRunning(true);
    // The command line's options (drape simulate --integrator static), with the
    // view's rest criteria: the same input gives the same rest state.
    cloth::RestOptions opt;
    opt.integrator = cloth::Integrator::Static;
    // One BLAS thread, as the command line runs: the factorisation's rounding,
    // and with it the fold branch a buckling drape takes, is then the same.
    cloth::single_threaded_blas();
    opt.residual = m_restResidual;
    opt.max_speed = m_restSpeed;
    if (maxNewton > 0) opt.max_newton = maxNewton;
    opt.cancel = &m_cancel;
    double r0 = -1, fraction = 0;
    QString status;
    opt.progress = [&](const cloth::SolverStatus& st) {
        // Progress: the residual's way down to the target on a log scale. A
        // continuation solve starts again on each grid: the fraction never goes back.
        if (r0 < 0 && st.residual > 0) r0 = st.residual;
        if (r0 > opt.residual && st.residual > 0)
            fraction = std::max(fraction, std::clamp(std::log(r0 / st.residual) / std::log(r0 / opt.residual), 0.0, 0.99));
        status = QStringLiteral("Newton iteration %1, residual %2").arg(st.newton_iterations).arg(st.residual, 0, 'g', 3);
        if (m_uiReady && m_sincePublish.elapsed() > kFrameIntervalMs) publish(false, fraction, status);
        return !m_cancel.load();
    };
    publish(true, 0.0, QStringLiteral("draping to rest"));
    try {
        cloth::SolverStatus st;
        const bool fresh = pristine() && maxNewton < 0;
        if (fresh && m_spec->shape == Drape::Disc && m_spec->setup.grid >= cloth::kCoarsestLevel && !m_spec->preset.is_seed()) {
            // The drapemeter from its start, on grid 41 or finer: the engine's
            // own drape (finer than 41: grid 41 first, then this one), exactly
            // what `drape simulate` runs. Shown when it is done.
            const cloth::DrapeResult r = cloth::simulate_drape(m_spec->preset.material(), m_spec->setup, opt, m_spec->preset.model);
            st = r.status;
            if (st.outcome != cloth::SolverStatus::Outcome::Cancelled) m_sys->x = r.x;
        } else if (fresh && m_spec->shape == Drape::Skirt) {
            // A skirt from its flat pattern: the settling fall, then the static
            // solve, exactly what `drape garment` runs (with its iteration budget).
            opt.max_newton = importers::garment_rest_options().max_newton;
            st = importers::settle_to_rest(*m_sys, opt);
        } else if (fresh && m_spec->shape == Drape::Disc) {
            // The drapemeter from its start on a grid below 41, on the shown
            // system (live frames): laid as `drape simulate` lays it
            // (DrapeSetup::laying_load: the preset's lab's), then at rest.
            st = cloth::rest_from_flat(*m_sys, m_spec->setup, opt);
        } else {
            st = cloth::run_to_rest(*m_sys, opt);
        }
        m_touched = true;
        m_steps += st.steps;
        m_sys->v.setZero();
        setRunning(false);
        publish(true, st.converged() ? 1.0 : fraction, describeSolve(st));
        if (st.converged()) {
            if (maxNewton < 0) {
                computeResults(st);
                emit restReached(m_sys->time, st.residual);
            }
        } else if (st.outcome == cloth::SolverStatus::Outcome::NotConverged && maxNewton < 0) {
            // Stopped at the iteration budget: the shape is still worth reading back
            // (its status says so), and the error below says why it is not at rest.
            computeResults(st);
            emit errorOccurred(QStringLiteral("static solver: %1 after %2 iterations (residual %3)")
                                   .arg(QString::fromStdString(cloth::to_string(st.outcome)))
                                   .arg(st.newton_iterations)
                                   .arg(st.residual, 0, 'g', 3));
        } else if (st.outcome != cloth::SolverStatus::Outcome::Cancelled && maxNewton < 0) {
            emit errorOccurred(QStringLiteral("static solver: %1 after %2 iterations (residual %3)%4")
                                   .arg(QString::fromStdString(cloth::to_string(st.outcome)))
                                   .arg(st.newton_iterations)
                                   .arg(st.residual, 0, 'g', 3)
                                   .arg(st.message.empty() ? QString() : QStringLiteral(": ") + QString::fromStdString(st.message)));
        }
    } catch (const std::exception& e) {
        setRunning(false);
        fail(QStringLiteral("static solver"), e);
    }
    m_cancel = false;
}

void DrapeWorker::computeResults(const cloth::SolverStatus& status)
{
    if (!m_sys || !m_mesh || !m_spec) return;
    try {
        auto r = std::make_shared<DrapeResults>();
        r->generation = m_mesh->generation;
        r->status = status;
        r->x = m_sys->x;
        if (isDrapemeter(m_spec->shape)) r->drape = cloth::measure_drape(*m_sys, m_spec->setup);
        if (m_body) r->penetration = importers::body_penetration(*m_body, m_sys->x);
        emit resultsReady(r);
    } catch (const std::exception& e) {
        fail(QStringLiteral("measure the rest state"), e);
    }
}

void DrapeWorker::stepOnce()
{
    if (!m_sys) return;
    m_touched = true;
    setRunning(false);
    if (m_integ == cloth::Integrator::Static) {
        runStatic(1); // one Newton iteration
        return;
    }
    try {
        if (!m_stepper) makeStepper();
        if (!m_stepper->step(effectiveTimeStep()))
            emit errorOccurred(QStringLiteral("the simulation diverged: use a smaller time step; press reset"));
        else
            ++m_steps;
    } catch (const std::exception& e) {
        fail(QStringLiteral("simulation step"), e);
    }
    publish(true);
}

void DrapeWorker::reset()
{
    if (!m_sys) return;
    const bool wasRunning = m_running;
    setRunning(false);
    m_sys->x = m_x0;
    m_sys->v.setZero(m_sys->vertex_count(), 3);
    m_sys->time = 0;
    m_steps = 0;
    m_touched = false;
    remakeStepper(); // integrators may keep history (e.g. factorisations)
    publish(true);
    if (wasRunning) play();
}

void DrapeWorker::setPinned(int vertex, bool pinned)
{
    if (!m_sys) return;
    try {
        if (vertex < 0 || vertex >= m_sys->vertex_count())
            throw ParameterError("pin: vertex " + std::to_string(vertex) + " is not in [0, " +
                                 std::to_string(m_sys->vertex_count()) + ")");
        m_sys->set_pinned(vertex, pinned);
        m_touched = true;
        if (pinned) m_sys->v.row(vertex).setZero();
    } catch (const std::exception& e) {
        fail(QStringLiteral("pin"), e);
    }
    publish(true);
}

void DrapeWorker::clearPins()
{
    if (!m_sys) return;
    for (int i = 0; i < m_sys->vertex_count(); ++i)
        if (m_sys->pinned(i)) m_sys->set_pinned(i, false);
    publish(true);
}

void DrapeWorker::setMass(int vertex, double kg)
{
    if (!m_sys) return;
    try {
        if (vertex < 0 || vertex >= m_sys->vertex_count())
            throw ParameterError("mass: vertex " + std::to_string(vertex) + " is not in [0, " +
                                 std::to_string(m_sys->vertex_count()) + ")");
        if (!(kg > 0) || !std::isfinite(kg))
            throw ParameterError("mass: vertex " + std::to_string(vertex) + " mass " + std::to_string(kg) +
                                 " kg must be a positive number");
        m_sys->set_mass(vertex, kg);
        m_touched = true;
    } catch (const std::exception& e) {
        fail(QStringLiteral("vertex mass"), e);
    }
    publish(true);
}

void DrapeWorker::addSphere(SphereSpec s)
{
    if (!m_sys) return;
    try {
        if (!s.centre.allFinite() || !(s.radius > 0) || !std::isfinite(s.radius))
            throw ParameterError("sphere collider: radius " + std::to_string(s.radius) + " m must be positive and the centre finite");
        m_sys->add_collider(std::make_shared<cloth::SphereCollider>(s.centre, s.radius));
        m_touched = true;
        makeStepper(); // contact blocks may be part of the implicit solver's pattern
        emitMesh();
        publish(true);
    } catch (const std::exception& e) {
        fail(QStringLiteral("add sphere"), e);
    }
}

void DrapeWorker::clearExtraColliders()
{
    if (!m_sys) return;
    m_sys->clear_colliders();
    for (const auto& c : m_baseColliders) m_sys->add_collider(c);
    remakeStepper();
    emitMesh();
    publish(true);
}

void DrapeWorker::setOutlineWanted(bool on)
{
    m_outline = on;
    if (!on) m_lastOutline.clear();
    publish(true);
}

void DrapeWorker::publish(bool force, double fraction, const QString& status)
{
    if (!m_sys || !m_mesh) return;
    if (!force && !m_uiReady) return; // the GUI still has the previous frame: skip, never queue up
    if (!force && m_sincePublish.elapsed() < kFrameIntervalMs) return;
    m_sincePublish.restart();
    auto f = std::make_shared<DrapeFrame>();
    const int n = m_sys->vertex_count();
    f->generation = m_mesh->generation;
    f->x = m_sys->x;
    f->simTime = m_sys->time;
    f->steps = m_steps;
    f->maxSpeed = maxFreeSpeed(*m_sys);
    const cloth::Triangles& F = m_sys->mesh().F;
    f->vertices = packVertices(f->x, F, m_texcoord);
    for (int i = 0; i < n; ++i)
        if (m_sys->pinned(i)) f->pinned.push_back(i);
    f->mass = std::make_shared<const Eigen::VectorXd>(m_sys->model().mass);
    f->fraction = fraction;
    f->status = status;
    if (m_outline) {
        // The shadow outline costs a pass over all triangles: refresh it a few times a second.
        if (force || m_lastOutline.empty() || m_sinceOutline.elapsed() > 200) {
            try {
                m_lastOutline = cloth::shadow_outline(f->x, F, 720);
            } catch (const std::exception&) {
                m_lastOutline.clear();
            }
            m_sinceOutline.restart();
        }
        f->outline = m_lastOutline;
    }
    m_uiReady = false;
    emit frameReady(f);
}

void DrapeWorker::saveResults(const QString& jsonPath, const QString& integratorName)
{
    if (!m_sys || !m_spec) {
        emit errorOccurred(QStringLiteral("save results: there is no cloth yet"));
        return;
    }
    try {
        const SolverSettings solver{integratorName, effectiveTimeStep(), m_restSpeed, m_restResidual, m_steps};
        const QString objPath = saveDrapeResults(jsonPath, *m_sys, *m_spec, solver, m_texcoord);
        emit resultsSaved(jsonPath, objPath);
    } catch (const std::exception& e) {
        fail(QStringLiteral("save results to '%1'").arg(jsonPath), e);
    }
}

} // namespace drape::widget
