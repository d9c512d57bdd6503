#include "engine/cloth/drape.hpp"

#include "engine/core/error.hpp"
#include "engine/core/units.hpp"

#include <Eigen/Dense>

#include <cmath>
#include <numbers>
#include <cstdlib>
#include <random>

namespace drape::cloth {

void DrapeSetup::validate() const
{
    auto positive = [](const char* name, double v) {
        if (!std::isfinite(v) || !(v > 0))
            throw ParameterError(std::string(name) + " = " + format_double(v) + " m must be a positive length");
    };
    positive("sample diameter", sample_diameter);
    positive("disc diameter", disc_diameter);
    positive("pedestal height", pedestal_height);
    if (sample_diameter <= disc_diameter)
        throw ParameterError("sample diameter " + format_double(sample_diameter) + " m must be larger than the disc diameter " +
                             format_double(disc_diameter) + " m");
    if (sample_diameter > 5.0) throw ParameterError("sample diameter " + format_double(sample_diameter) + " m is larger than 5 m");
    if (!(edge_radius >= 0) || edge_radius >= disc_diameter / 2)
        throw ParameterError("pedestal edge radius " + format_double(edge_radius) + " m must be in [0, disc radius)");
    if (grid < 5 || grid > 1000) throw ParameterError("grid = " + std::to_string(grid) + " must be in [5, 1000]");
    // Below grid 17 the rim band's first refined ring lands past the rim and the
    // triangles between a coarse ring and the band turn into slivers (8-12
    // degrees at grids 6-11 on 300/150 mm); the rings exist to resolve the rim.
    if (mesh == DrapeMesh::Rings && grid < kMinRingsGrid)
        throw ParameterError("grid = " + std::to_string(grid) + " is too coarse for the ring mesh (at least " + std::to_string(kMinRingsGrid) +
                             ": the rim's refined band needs rings either side of it)");
    if (!(perturbation >= 0) || perturbation > 0.05)
        throw ParameterError("perturbation = " + format_double(perturbation) + " m must be in [0, 0.05]");
    if (!specimen_offset.allFinite() || specimen_offset.norm() >= disc_diameter / 2)
        throw ParameterError("specimen offset (" + format_double(specimen_offset.x()) + ", " + format_double(specimen_offset.y()) +
                             ") m must be finite and within the disc radius " + format_double(disc_diameter / 2) + " m");
    if (!density_gradient.allFinite() || density_gradient.norm() >= 1)
        throw ParameterError("density gradient (" + format_double(density_gradient.x()) + ", " + format_double(density_gradient.y()) +
                             ") per specimen radius must be finite and shorter than 1 (the density would reach 0)");
    if (fold_mode != 0 && (fold_mode < 2 || fold_mode > 16))
        throw ParameterError("fold mode = " + std::to_string(fold_mode) + " must be 0 (seeded mix) or a fold count in [2, 16]");
    if (std::isinf(fold_angle)) throw ParameterError("fold angle = " + format_double(fold_angle) + " rad must be finite (or NaN: the seeded phase)");
    if (!(laying_load > 0) || laying_load > 1)
        throw ParameterError("laying load = " + format_double(laying_load) + " must be a fraction of gravity in (0, 1]");
    for (double d : slice_depths)
        if (!(d > 0) || !std::isfinite(d)) throw ParameterError("slice depth " + format_double(d) + " m must be positive");
}

const char* to_string(DrapeMesh m)
{
    switch (m) {
    case DrapeMesh::Grid: return "grid";
    case DrapeMesh::Rings: return "rings";
    }
    return "grid";
}

DrapeMesh drape_mesh_from_string(const std::string& s)
{
    if (s == "grid") return DrapeMesh::Grid;
    if (s == "rings") return DrapeMesh::Rings;
    throw ParameterError("mesh \"" + s + "\" is not one of grid, rings");
}

RingGrading drapemeter_rim_grading(const DrapeSetup& setup)
{
    const double a = setup.disc_diameter / 2;
    RingGrading g;
    g.inner_radius = std::max(0.0, a - 0.010);
    g.outer_radius = a + 0.015;
    g.factor = 0.4;
    g.taper = 0.015;
    return g;
}

ClothMesh make_drape_mesh(const DrapeSetup& setup)
{
    if (setup.mesh == DrapeMesh::Rings) return make_ring_disc(setup.sample_diameter, setup.grid, drapemeter_rim_grading(setup), 0.0);
    return make_disc(setup.sample_diameter, setup.grid, 0.0);
}

namespace {

/// Lifts the overhanging part of the flat sheet by a seeded mix of harmonics
/// (DrapeSetup::perturbation documents the form).
void perturb(Positions& X, const DrapeSetup& setup)
{
    if (setup.perturbation <= 0) return;
    std::mt19937_64 rng(setup.seed);
    std::uniform_real_distribution<double> U(0.0, 1.0);
    double a[17], ph[17];
    for (int k = 2; k <= 16; ++k) {
        a[k] = U(rng);
        ph[k] = 2 * std::numbers::pi * U(rng);
    }
    const double R1 = setup.sample_diameter / 2, R2 = setup.disc_diameter / 2;
    Eigen::VectorXd lift(X.rows());
    double mx = 0;
    for (int i = 0; i < X.rows(); ++i) {
        const double r = std::hypot(X(i, 0), X(i, 1));
        const double th = std::atan2(X(i, 1), X(i, 0));
        const double t = std::max(0.0, r - R2) / (R1 - R2);
        double s = 0;
        for (int k = 2; k <= 16; ++k) s += a[k] * std::cos(k * th + ph[k]);
        if (setup.fold_mode >= 2) {
            // One dominant mode: the mix is normalised to at most 1 (sum of a_k
            // below 15), then a tenth of it rides on the n-fold cosine.
            const double phase = std::isfinite(setup.fold_angle) ? -setup.fold_mode * setup.fold_angle : ph[setup.fold_mode];
            s = std::cos(setup.fold_mode * th + phase) + 0.1 * s / 15.0;
        }
        lift(i) = s * t * t;
        mx = std::max(mx, std::abs(lift(i)));
    }
    if (mx > 0)
        for (int i = 0; i < X.rows(); ++i) X(i, 2) += setup.perturbation * lift(i) / mx;
}

} // namespace

Positions interpolate_positions(const ClothMesh& coarse, const Positions& xc, const ClothMesh& fine)
{
    // Buckets of the coarse mesh's spacing: the grid's cell, or a general
    // mesh's longest edge in material coordinates.
    double cell = std::max(coarse.grid.hu, coarse.grid.hv);
    if (!coarse.grid.valid()) {
        cell = 0;
        for (int t = 0; t < coarse.F.rows(); ++t)
            for (int c = 0; c < 3; ++c)
                cell = std::max(cell, (coarse.uv.row(coarse.F(t, c)) - coarse.uv.row(coarse.F(t, (c + 1) % 3))).norm());
        if (!(cell > 0)) throw ParameterError("interpolate_positions: the coarse mesh has no extent");
    }
    const Eigen::Vector2d lo = coarse.uv.colwise().minCoeff().transpose() - Eigen::Vector2d::Constant(cell);
    const Eigen::Vector2d hi = coarse.uv.colwise().maxCoeff().transpose() + Eigen::Vector2d::Constant(cell);
    const int nx = static_cast<int>((hi.x() - lo.x()) / cell) + 1, ny = static_cast<int>((hi.y() - lo.y()) / cell) + 1;
    std::vector<std::vector<int>> buckets(static_cast<std::size_t>(nx * ny));
    auto bucket_of = [&](double x, double y, int& bx, int& by) {
        bx = std::clamp(static_cast<int>((x - lo.x()) / cell), 0, nx - 1);
        by = std::clamp(static_cast<int>((y - lo.y()) / cell), 0, ny - 1);
    };
    for (int t = 0; t < coarse.F.rows(); ++t) {
        Eigen::Vector2d bmin = Eigen::Vector2d::Constant(1e300), bmax = -bmin;
        for (int c = 0; c < 3; ++c) {
            bmin = bmin.cwiseMin(coarse.uv.row(coarse.F(t, c)).transpose());
            bmax = bmax.cwiseMax(coarse.uv.row(coarse.F(t, c)).transpose());
        }
        int x0, y0, x1, y1;
        bucket_of(bmin.x(), bmin.y(), x0, y0);
        bucket_of(bmax.x(), bmax.y(), x1, y1);
        for (int by = y0; by <= y1; ++by)
            for (int bx = x0; bx <= x1; ++bx) buckets[static_cast<std::size_t>(bx + nx * by)].push_back(t);
    }
    Positions out(fine.vertex_count(), 3);
    for (int i = 0; i < fine.vertex_count(); ++i) {
        const Eigen::Vector2d p = fine.uv.row(i).transpose();
        int bx, by;
        bucket_of(p.x(), p.y(), bx, by);
        double best = -1e300;
        Eigen::Vector3d bestb(1, 0, 0);
        int bestt = -1;
        for (int r = 0; r <= 3 && (bestt < 0 || best < -1e-9); ++r) {
            for (int yy = by - r; yy <= by + r; ++yy)
                for (int xx = bx - r; xx <= bx + r; ++xx) {
                    if (xx < 0 || yy < 0 || xx >= nx || yy >= ny) continue;
                    if (std::max(std::abs(xx - bx), std::abs(yy - by)) != r) continue;
                    for (int t : buckets[static_cast<std::size_t>(xx + nx * yy)]) {
                        const Eigen::Vector2d a = coarse.uv.row(coarse.F(t, 0)), b = coarse.uv.row(coarse.F(t, 1)), c = coarse.uv.row(coarse.F(t, 2));
                        Eigen::Matrix2d T;
                        T << b - a, c - a;
                        const double det = T.determinant();
                        if (std::abs(det) < 1e-300) continue;
                        const Eigen::Vector2d l = T.inverse() * (p - a);
                        const Eigen::Vector3d bc(1 - l.x() - l.y(), l.x(), l.y());
                        if (bc.minCoeff() > best) {
                            best = bc.minCoeff();
                            bestb = bc;
                            bestt = t;
                        }
                    }
                }
        }
        if (bestt < 0) {
            out.row(i) = fine.X.row(i);
            continue;
        }
        out.row(i) = bestb(0) * xc.row(coarse.F(bestt, 0)) + bestb(1) * xc.row(coarse.F(bestt, 1)) + bestb(2) * xc.row(coarse.F(bestt, 2));
    }
    return out;
}

std::unique_ptr<ClothSystem> make_drape_system(const Material& fabric, const DrapeSetup& setup, const ModelOptions& mopt)
{
    setup.validate();
    ClothMesh mesh;
    ClothModel model;
    if (mopt.arc_membrane && setup.mesh != DrapeMesh::Grid)
        throw ParameterError("springs that measure arcs (model.arc_membrane) are the grid's; the " + std::string(to_string(setup.mesh)) +
                             " mesh has the triangle model's fibre membrane");
    if (!fabric.grid_springs) {
        mesh = make_drape_mesh(setup);
        model = make_model(mesh, fabric.params, mopt);
    } else {
        const GridSprings& g = *fabric.grid_springs;
        if (setup.mesh != DrapeMesh::Grid)
            throw ParameterError("the grid springs (a seed-19 preset) need the grid mesh, not " + std::string(to_string(setup.mesh)));
        g.validate("grid springs");
        if (std::abs(g.width - setup.sample_diameter) > 1e-6)
            throw ParameterError("the grid springs (a seed-19 preset) describe a " + format_value(g.width * 1000) +
                                 " mm sheet but the sample diameter is " + format_value(setup.sample_diameter * 1000) + " mm");
        if (g.cells_u != g.cells_v || g.width != g.height)
            throw ParameterError("the drapemeter needs a round sheet: a square grid of square cells (got " +
                                 format_value(g.width * 1000) + " x " + format_value(g.height * 1000) + " mm, " +
                                 std::to_string(g.cells_u) + " x " + std::to_string(g.cells_v) + " cells)");
        mesh = make_disc(setup.sample_diameter, g.cells_u + 1, 0.0);
        ModelOptions o = mopt;
        if (o.bending == BendingModel::Quadratic) o.bending = BendingModel::Flexion;
        model = make_grid_spring_model(mesh, g, o);
    }
    if (setup.density_gradient.squaredNorm() > 0)
        for (int i = 0; i < mesh.vertex_count(); ++i)
            model.mass(i) *= 1 + setup.density_gradient.dot(Eigen::Vector2d(mesh.X(i, 0), mesh.X(i, 1))) / (setup.sample_diameter / 2);
    const Eigen::Vector3d offset(setup.specimen_offset.x(), setup.specimen_offset.y(), 0.0);
    // Static friction holds the specimen's centre on the disc (see HorizontalAnchor):
    // the material centre is tethered horizontally to the pedestal axis, stiff
    // enough that the whole weight pulling sideways would move it 0.1 mm. On an odd
    // grid the centre is a vertex; on an even grid it is the middle of a cell (its
    // four corners, a quarter each), so the set-up stays symmetric about the axis.
    {
        const double weight = model.total_mass() * model.gravity.norm();
        const double k = weight / 1e-4;
        HorizontalAnchor centre;
        centre.target = offset;
        centre.k = k;
        const GridInfo& g = mesh.grid;
        const int mid = g.nu / 2;
        if (g.valid() && g.nu == g.nv && g.nu % 2 == 0 && g.at(mid - 1, mid - 1) >= 0 && g.at(mid, mid - 1) >= 0 &&
            g.at(mid - 1, mid) >= 0 && g.at(mid, mid) >= 0) {
            centre.n = 4;
            centre.v = {g.at(mid - 1, mid - 1), g.at(mid, mid - 1), g.at(mid - 1, mid), g.at(mid, mid)};
            centre.w = {0.25, 0.25, 0.25, 0.25};
        } else {
            int c = 0;
            double best = 1e300;
            for (int i = 0; i < mesh.vertex_count(); ++i)
                if (const double r = std::hypot(mesh.X(i, 0), mesh.X(i, 1)); r < best) {
                    best = r;
                    c = i;
                }
            centre.v[0] = c;
            centre.target = Eigen::Vector3d(mesh.X(c, 0), mesh.X(c, 1), 0.0) + offset;
        }
        model.anchors.push_back(centre);
        if (setup.disc_grip)
            for (int i = 0; i < mesh.vertex_count(); ++i) {
                bool is_centre = false;
                for (int j = 0; j < centre.n; ++j) is_centre |= centre.v[static_cast<std::size_t>(j)] == i;
                const Eigen::Vector3d laid = Eigen::Vector3d(mesh.X(i, 0), mesh.X(i, 1), 0.0) + offset;
                if (!is_centre && std::hypot(laid.x(), laid.y()) < setup.disc_diameter / 2)
                    model.anchors.push_back(HorizontalAnchor::at_vertex(i, laid, k));
            }
    }
    auto sys = std::make_unique<ClothSystem>(std::move(mesh), std::move(model));
    place_on_drapemeter(*sys, setup);
    return sys;
}

void place_on_drapemeter(ClothSystem& sys, const DrapeSetup& setup)
{
    // Start flat, just above the pedestal top (offset by half the thickness).
    sys.x.col(2).setConstant(sys.model().contact_offset + 1e-6);
    perturb(sys.x, setup);
    sys.x.col(0).array() += setup.specimen_offset.x();
    sys.x.col(1).array() += setup.specimen_offset.y();
    const double R2 = setup.disc_diameter / 2;
    sys.add_collider(std::make_shared<PedestalCollider>(Eigen::Vector3d::Zero(), R2, setup.pedestal_height,
                                                        std::min(setup.edge_radius, 0.5 * R2)));
    if (setup.floor)
        sys.add_collider(std::make_shared<PlaneCollider>(Eigen::Vector3d(0, 0, -setup.pedestal_height), Eigen::Vector3d::UnitZ()));
}

DrapeResult measure_drape(const ClothSystem& s, const DrapeSetup& setup, const MetricOptions& mopt)
{
    DrapeResult r;
    r.x = s.x;
    r.outline = shadow_outline(s.x, s.mesh().F);
    r.metrics = drape_metrics(r.outline, setup.sample_diameter / 2, setup.disc_diameter / 2, mopt);
    r.hem = hem_profile(s.x, s.mesh().boundary);
    for (double d : setup.slice_depths) r.slices.push_back({d, slice_profile(s.x, s.mesh().F, -d, 360)});
    return r;
}

RestOptions from_flat_options(RestOptions ropt, const DrapeSetup& setup)
{
    // A drape from the random mix shifts the exact Hessian near rest
    // (RestOptions::late_shift_residual): it leaves a saddle there at Newton's pace
    // instead of creeping off it. A prescribed fold branch (the fits' drapes on the
    // record's branch) keeps the solver's path: shifting there too moved six of the
    // ten set-a fits' optima (chi2 -2.3 .. +14) for no clear gain
    // (docs/decisions/0023-late-shift-from-flat.md).
    if (ropt.late_shift_residual == 0 && setup.fold_mode == 0) ropt.late_shift_residual = kLateShiftResidual;
    return ropt;
}

SolverStatus rest_from_flat(ClothSystem& sys, const DrapeSetup& setup, const RestOptions& ropt_in)
{
    const RestOptions ropt = from_flat_options(ropt_in, setup);
    if (ropt.integrator != Integrator::Static || !(setup.laying_load < 1)) return run_to_rest(sys, ropt);
    // The first rest under part of the load (DrapeSetup::laying_load), then the
    // whole load from there.
    const Eigen::Vector3d g = sys.model().gravity;
    sys.model().gravity = setup.laying_load * g;
    RestOptions lo = ropt;
    lo.residual = std::max(ropt.residual, 1e-4); // the full load's solve polishes
    lo.checkpoint = nullptr; // the whole load's solve reports its checkpoint
    SolverStatus pre;
    try {
        pre = run_to_rest(sys, lo);
    } catch (...) {
        sys.model().gravity = g;
        throw;
    }
    sys.model().gravity = g;
    if (pre.outcome == SolverStatus::Outcome::Cancelled) return pre;
    RestOptions full = ropt;
    if (ropt.checkpoint)
        full.checkpoint = [&ropt, &pre](const Positions& x, const SolverStatus& at) {
            SolverStatus with = at;
            with.add_work(pre);
            ropt.checkpoint(x, with);
        };
    SolverStatus st = run_to_rest(sys, full);
    st.add_work(pre);
    return st;
}

int continuation_level(int grid)
{
    if (grid <= kCoarsestLevel) return 0;
    int coarse = kCoarsestLevel;
    for (int level = 2 * kCoarsestLevel - 1; level < grid; level = 2 * level - 1) coarse = level;
    return coarse;
}

DrapeResult simulate_drape(const Material& fabric, const DrapeSetup& setup, const RestOptions& ropt_in, const ModelOptions& mopt,
                           const LevelRest* start, std::vector<LevelRest>* levels)
{
    RestOptions ropt = from_flat_options(ropt_in, setup);
    ropt.checkpoint = nullptr; // its own below (`levels`)
    auto sys = make_drape_system(fabric, setup, mopt);
    const bool static_levels = ropt.integrator == Integrator::Static && !fabric.grid_springs;
    const bool continuation = static_levels && setup.grid > kCoarsestLevel;
    const double level_residual = std::max(ropt.residual, kLevelResidual);
    SolverStatus pre;
    bool polish = false; // the finer level starts on the coarse level's rest
    if (continuation) {
        // Intermediate levels have an odd grid: a node then sits on the axis, the
        // centre anchor holds the sheet there, and turning about the axis costs
        // nothing. On an even grid the anchored node is h/sqrt(2) off the axis, the
        // energy depends weakly on that turn, and Newton drifts along it: cotton
        // starter at grid 100, the grid-50 level turned 18 degrees over 627
        // iterations, the grid-51 level took 96 (the whole drape 1,108 -> 500
        // Newton iterations, D 58.254 -> 58.256 %).
        //
        // The levels are one nested set for every target, 41, 81, 161, 321 (the
        // largest below the target): the fold branch is chosen where a drape
        // from flat at grid 41 chooses it and carried through the same levels
        // whatever the target, so grids 61 and 81 show the branch grid 41 shows.
        // With a level halfway to each target (61 -> 31) the cotton starter came
        // out with 7 folds at grid 61 and 8 at 41 and 81. The coarsest level was
        // 25 until 2026-11-30: a 12.5 mm mesh picked branches the finer meshes do
        // not keep - the denim starter with the crest-corrected stencils came to
        // rest at grid 25 and 41 in an uneven 6-fold state (D 72.7 % at 41) that
        // relaxed to an even one at 61 (74.1 %), while the drape from flat at 41
        // made 5 folds (70.1 %) of lower energy at 41 and at 61
        // (docs/decisions/0012-coarsest-level-41.md).
        //
        // The same levels on a prescribed fold branch (fold_mode n, what the fits
        // drape on). Grid 25 kept a 5-fold lift of the DL-A09 fit's preset that
        // grid 41 from flat loses (7 folds), but the set-a fits with grid 25 as
        // the coarsest level on the branch starts (and 41 from random starts)
        // were slower per drape (3.4 s against 1.8-2.3 s) and as good or worse
        // on every count (the same record).
        DrapeSetup coarse = setup;
        coarse.grid = continuation_level(setup.grid);
        const ClothMesh cm = make_drape_mesh(coarse);
        LevelRest rc;
        if (start && start->grid == coarse.grid && start->residual == level_residual && start->x.rows() == cm.vertex_count()) {
            rc = *start; // solved before (the same solve)
        } else {
            RestOptions co = ropt;
            co.residual = level_residual; // the fine solve polishes
            DrapeResult d = simulate_drape(fabric, coarse, co, mopt, nullptr, levels);
            rc = {coarse.grid, level_residual, std::move(d.x), d.status};
            // (Its own checkpoint is its end: already in `levels`.)
        }
        if (rc.status.outcome != SolverStatus::Outcome::Diverged && rc.status.outcome != SolverStatus::Outcome::Cancelled) {
            sys->x = interpolate_positions(cm, rc.x, sys->mesh());
            polish = true;
        }
        pre = rc.status;
    }
    // This grid's own level rest, when it is one of the levels.
    RestOptions last = ropt;
    if (levels && static_levels && setup.grid >= kCoarsestLevel && continuation_level(2 * setup.grid - 1) == setup.grid) {
        last.checkpoint_residual = level_residual;
        last.checkpoint = [&](const Positions& x, const SolverStatus& at) {
            SolverStatus with = at;
            with.add_work(pre);
            levels->push_back({setup.grid, level_residual, x, with});
        };
    }
    DrapeResult r;
    if (continuation) {
        // The finer level starts on the coarse level's fold branch and only
        // polishes it: where the exact Hessian is indefinite there (the rim,
        // compressed fold flanks), a shifted exact Hessian goes on at Newton's
        // pace, where the projected one crept for 1,000-2,000 iterations at grid 81
        // (docs/decisions/0022-fine-level-shift.md).
        // (A coarse level that diverged or was cancelled leaves the flat start:
        // then the usual order, as from flat.)
        RestOptions fine = last;
        // (A negative value, off, reaches the solver, which shifts only when it is positive.)
        if (fine.shift_before_projection == 0 && polish) fine.shift_before_projection = kFineShiftPseudoTime;
        r.status = run_to_rest(*sys, fine);
        r.status.add_work(pre);
    } else {
        r.status = rest_from_flat(*sys, setup, last); // laid as the set-up says
    }
    DrapeResult m = measure_drape(*sys, setup);
    m.potential_energy = sys->potential_energy(sys->x);
    m.status = r.status;
    return m;
}

DrapeResult simulate_drape_from(const Material& fabric, const DrapeSetup& setup, const Positions& start, const RestOptions& ropt,
                                const ModelOptions& mopt)
{
    auto sys = make_drape_system(fabric, setup, mopt);
    if (start.rows() != sys->vertex_count())
        throw ParameterError("warm start has " + std::to_string(start.rows()) + " vertices, the drape mesh " +
                             std::to_string(sys->vertex_count()));
    sys->x = start;
    DrapeResult r;
    const SolverStatus st = run_to_rest(*sys, ropt);
    r = measure_drape(*sys, setup);
    r.potential_energy = sys->potential_energy(sys->x);
    r.status = st;
    return r;
}

} // namespace drape::cloth
