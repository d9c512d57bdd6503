// The drapemeter experiment at small grids: it converges, is plausible,
// reproducible per seed, warm starts pay, and bad set-ups are refused.
#include "engine/cloth/blas_threads.hpp"
#include "engine/cloth/drape.hpp"
#include "engine/core/error.hpp"

#include <QTest>

#include <dlfcn.h>
#include <strings.h>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <numbers>
#include <thread>

using namespace drape::cloth;

namespace {
DrapeSetup small(int grid = 25, std::uint64_t seed = 1)
{
    DrapeSetup s;
    s.grid = grid;
    s.seed = seed;
    return s;
}
} // namespace

class TestDrape : public QObject {
    Q_OBJECT
private slots:
    // First in this process: no factorisation has run yet.
    void the_first_drape_rounds_as_every_later_one()
    {
        // OpenBLAS's default thread count follows the machine (and OMP_NUM_THREADS);
        // the sparse solver's factorisation rounds differently with more threads,
        // and a buckling drape can then take another fold branch. The first
        // factorisation must switch to one thread whatever the default was: a
        // drape made before anything called single_threaded_blas() (a test's
        // synthetic record) equals one made after, bit for bit.
        using SetThreads = void (*)(int);
        auto set_threads = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));
        if (set_threads) set_threads(2); // as on a two-core machine without OMP_NUM_THREADS
        const DrapeResult first = simulate_drape(FabricParams(), small(41));
        single_threaded_blas();
        const DrapeResult later = simulate_drape(FabricParams(), small(41));
        QCOMPARE(first.status.newton_iterations, later.status.newton_iterations);
        QVERIFY(first.x == later.x);
    }

    void blas_kernels_are_the_portable_ones()
    {
        // After the first factorisation (above) OpenBLAS sums with the kernels every
        // AVX2 machine has (portable_blas_kernel): a fit's fold branches, hence its
        // numbers, are then the same on every such machine.
        const std::string kernel = portable_blas_kernel();
        qInfo("BLAS kernels: %s", kernel.c_str());
        QCOMPARE(blas_kernel(), kernel);
        if (kernel == "not OpenBLAS") QSKIP("another BLAS than OpenBLAS in this process");
        if (std::getenv("OPENBLAS_CORETYPE") || std::getenv("DRAPE_NATIVE_BLAS")) QSKIP("the user chose the kernels");
        if (!__builtin_cpu_supports("avx2") || !__builtin_cpu_supports("fma")) QSKIP("a machine without AVX2 and FMA keeps its own kernels");
        QVERIFY2(strcasecmp(kernel.c_str(), kPortableBlasKernel) == 0, kernel.c_str());
        QVERIFY(simulate_drape(FabricParams(), small(9)).status.converged()); // and they factorise
    }

    void a_worker_thread_factorises_without_openmp_regions()
    {
        // Debian's CHOLMOD opens OpenMP regions of four threads inside every
        // supernodal factorisation; the solver makes them inactive. OpenMP 5 keeps
        // that setting per thread, so it must be made on every thread that
        // factorises, not once for the process: a fit's two drapes on two worker
        // threads each took twice as long otherwise (futex waits in libgomp).
        using GetLevels = int (*)();
        auto get_levels = reinterpret_cast<GetLevels>(dlsym(RTLD_DEFAULT, "omp_get_max_active_levels"));
        if (!get_levels) QSKIP("no OpenMP runtime in the process (CHOLMOD built without it)");
        if (std::getenv("OMP_MAX_ACTIVE_LEVELS") || std::getenv("OMP_THREAD_LIMIT")) QSKIP("the user chose OpenMP's levels");
        QVERIFY(simulate_drape(FabricParams(), small(9)).status.converged()); // this thread first
        int before = -1, after = -1;
        bool converged = false;
        std::thread worker([&] {
            before = get_levels();
            converged = simulate_drape(FabricParams(), small(9)).status.converged();
            after = get_levels();
        });
        worker.join();
        if (before == 0) QSKIP("this OpenMP runtime keeps max-active-levels for the whole process (libgomp before GCC 11)");
        QVERIFY(converged);
        QCOMPARE(after, 0);
    }

    void static_drape_converges_and_is_plausible_data()
    {
        QTest::addColumn<int>("mesh");
        QTest::newRow("grid") << static_cast<int>(DrapeMesh::Grid);
        QTest::newRow("rings") << static_cast<int>(DrapeMesh::Rings);
    }
    void static_drape_converges_and_is_plausible()
    {
        QFETCH(int, mesh);
        DrapeSetup setup = small();
        setup.mesh = static_cast<DrapeMesh>(mesh);
        const DrapeResult r = simulate_drape(FabricParams(), setup);
        QVERIFY2(r.status.converged(), r.status.message.c_str());
        QVERIFY(r.status.residual < 1e-6);
        const auto& m = r.metrics;
        QVERIFY2(m.drape_coefficient_percent > 15 && m.drape_coefficient_percent < 90, qPrintable(QString::number(m.drape_coefficient_percent)));
        QVERIFY(m.node_count >= 3 && m.node_count <= 12);
        // Hangs below the pedestal top, above the floor, outside the disc.
        QVERIFY(r.hem.min_z < -0.02 && r.hem.min_z > -0.12);
        QVERIFY(m.min_radius_m > 0.075 - 1e-3);
        // Nothing inside the pedestal beyond the contact penalty's depth.
        for (int i = 0; i < r.x.rows(); ++i) {
            const double rr = std::hypot(r.x(i, 0), r.x(i, 1));
            if (rr < 0.075 - 1e-3) QVERIFY(r.x(i, 2) > -1e-4);
        }
        // Slices just under the top close around the pedestal.
        QVERIFY(r.slices.front().profile.complete());
    }

    void specimen_stays_centred_on_the_disc()
    {
        // A sheet on a frictionless disc is unstable against sliding sideways; the
        // centre's static friction must keep it on the pedestal, also at a loose tolerance.
        for (double tol : {1e-3, 1e-6}) {
            DrapeSetup s = small(24);
            RestOptions ro;
            ro.residual = tol;
            const DrapeResult r = simulate_drape(FabricParams(), s, ro);
            QVERIFY(r.status.converged());
            const Eigen::RowVector3d mean = r.x.colwise().mean();
            QVERIFY2(std::hypot(mean.x(), mean.y()) < 5e-3, qPrintable(QString("centroid off-axis by %1 m").arg(std::hypot(mean.x(), mean.y()))));
            QVERIFY(r.x.col(2).maxCoeff() > -1e-3); // still on the disc top
            QVERIFY(r.hem.min_z > -0.115);          // not lying on the floor
        }
    }

    void stiffer_fabric_drapes_higher()
    {
        FabricParams limp, stiff;
        stiff[Param::BendWarp] = stiff[Param::BendWeft] = 2e-4;
        const double d_limp = simulate_drape(limp, small()).metrics.drape_coefficient_percent;
        const double d_stiff = simulate_drape(stiff, small()).metrics.drape_coefficient_percent;
        QVERIFY2(d_stiff > d_limp + 10, qPrintable(QString("limp %1 %, stiff %2 %").arg(d_limp).arg(d_stiff)));
    }

    void same_seed_same_drape_other_seed_other_folds()
    {
        const DrapeResult a = simulate_drape(FabricParams(), small(25, 7));
        const DrapeResult b = simulate_drape(FabricParams(), small(25, 7));
        QCOMPARE(a.metrics.drape_coefficient_percent, b.metrics.drape_coefficient_percent);
        QVERIFY((a.x - b.x).cwiseAbs().maxCoeff() == 0.0);
        bool differs = false;
        for (std::uint64_t seed : {8, 9, 10}) {
            const DrapeResult c = simulate_drape(FabricParams(), small(25, seed));
            differs |= (c.x - a.x).cwiseAbs().maxCoeff() > 1e-3;
        }
        QVERIFY(differs);
    }

    void warm_start_after_small_change_is_cheap()
    {
        // A mid-weight fabric whose fold pattern survives a 10 % change. (A limp one
        // at this coarse grid may re-buckle into another fold count after the change,
        // and then the warm start costs nearly a cold one: 151 vs 191 iterations seen.)
        FabricParams p;
        p[Param::BendWarp] = 5e-5;
        p[Param::BendWeft] = 4e-5;
        const DrapeResult cold = simulate_drape(p, small());
        QVERIFY(cold.status.converged());
        p[Param::BendWarp] *= 1.1;
        p[Param::BendWeft] *= 1.1;
        const DrapeResult warm = simulate_drape_from(p, small(), cold.x);
        QVERIFY2(warm.status.converged(), warm.status.message.c_str());
        QVERIFY2(warm.status.newton_iterations * 3 < cold.status.newton_iterations,
                 qPrintable(QString("warm %1 vs cold %2 iterations").arg(warm.status.newton_iterations).arg(cold.status.newton_iterations)));
        QVERIFY(std::abs(warm.metrics.drape_coefficient_percent - cold.metrics.drape_coefficient_percent) < 5);
    }

    void finer_level_shift_keeps_the_rest_state()
    {
        // A finer grid's level polishes the coarse level's branch; where its exact
        // Hessian does not factorise, a larger proximal shift comes before the
        // projected Hessian (RestOptions::shift_before_projection, which
        // simulate_drape sets there). It changes the path's cost, not the drape:
        // the same grid-41 rest interpolated onto grid 45 and polished both ways.
        // A heavy anisotropic fabric laid as the lab lays it (DL-A07's fit of
        // 2026-12-01), whose grid-45 level has exact Hessians that do not
        // factorise; tst_starter_library (slow) measures the cotton starter at 81.
        FabricParams p;
        p[Param::AreaDensity] = 0.28;
        p[Param::BendWarp] = 3.96e-5;
        p[Param::BendWeft] = 1.49e-5;
        p[Param::Shear] = 29.7;
        p[Param::Thickness] = 6.5e-4;
        DrapeSetup coarse = small(kCoarsestLevel, 1);
        coarse.laying_load = 0.4;
        coarse.perturbation = 6e-3;
        ModelOptions mo;
        mo.bending_correction = true;
        const DrapeResult c = simulate_drape(p, coarse, {}, mo);
        QVERIFY2(c.status.converged(), c.status.message.c_str());
        DrapeSetup fine = coarse;
        fine.grid = 45;
        const Positions start = interpolate_positions(make_drape_mesh(coarse), c.x, make_drape_mesh(fine));
        RestOptions with_shift;
        with_shift.shift_before_projection = kFineShiftPseudoTime;
        const DrapeResult shifted = simulate_drape_from(p, fine, start, with_shift, mo);
        RestOptions projected_only; // neither shift: the projected Hessian at once
        projected_only.late_shift_residual = -1;
        const DrapeResult projected = simulate_drape_from(p, fine, start, projected_only, mo);
        QVERIFY2(projected.status.converged(), projected.status.message.c_str());
        QVERIFY2(shifted.status.converged(), shifted.status.message.c_str());
        qInfo("grid 45 from grid 41: %ld solver steps (%ld Newton iterations) with the shift, %ld (%ld) without; D %.4f / %.4f %%, %d / %d folds",
              shifted.status.steps, shifted.status.newton_iterations, projected.status.steps, projected.status.newton_iterations,
              shifted.metrics.drape_coefficient_percent, projected.metrics.drape_coefficient_percent, shifted.metrics.node_count,
              projected.metrics.node_count);
        // The case exercises the fallback: without the shift some exact Hessians did
        // not factorise (a step without a Newton iteration), and the paths differ.
        QVERIFY(projected.status.steps > projected.status.newton_iterations);
        QVERIFY(shifted.status.newton_iterations != projected.status.newton_iterations);
        QCOMPARE(shifted.metrics.node_count, projected.metrics.node_count);
        QVERIFY(std::abs(shifted.metrics.drape_coefficient_percent - projected.metrics.drape_coefficient_percent) < 0.01);
        QVERIFY(std::abs(shifted.potential_energy - projected.potential_energy) < 1e-6 * std::abs(projected.potential_energy));
        // Every factorisation counted, the failed ones too.
        QVERIFY(shifted.status.steps < projected.status.steps);
    }

    void late_shift_leaves_a_saddle_sooner()
    {
        // Near rest (relative residual below RestOptions::late_shift_residual) an
        // exact Hessian that does not factorise marks a saddle; a larger proximal
        // shift first lets the Newton step follow its negative curvature, where the
        // projected Hessian crept off it. The same rest state, fewer iterations.
        // DL-A09's fit (2026-12-02) at grid 25, laid as its lab lays it
        // (rest_from_flat: the path the widget's live drapes below grid 41 take).
        FabricParams p;
        p[Param::AreaDensity] = 0.38;
        p[Param::BendWarp] = 1.93e-5;
        p[Param::BendWeft] = 6.67e-5;
        p[Param::Shear] = 93.8;
        p[Param::Thickness] = 8.5e-4;
        p[Param::BucklingLength] = 0.0075;
        DrapeSetup s = small(25, 6);
        s.laying_load = 0.4;
        s.perturbation = 6e-3;
        ModelOptions mo;
        mo.bending_correction = true;
        RestOptions off;
        off.late_shift_residual = -1;
        const DrapeResult crept = simulate_drape(p, s, off, mo);
        const DrapeResult shifted = simulate_drape(p, s, {}, mo);
        QVERIFY2(crept.status.converged(), crept.status.message.c_str());
        QVERIFY2(shifted.status.converged(), shifted.status.message.c_str());
        qInfo("grid 25: %ld solver steps (%ld Newton iterations) with the late shift, %ld (%ld) without; D %.4f / %.4f %%, %d / %d folds",
              shifted.status.steps, shifted.status.newton_iterations, crept.status.steps, crept.status.newton_iterations,
              shifted.metrics.drape_coefficient_percent, crept.metrics.drape_coefficient_percent, shifted.metrics.node_count,
              crept.metrics.node_count);
        // A prescribed fold branch (the fits' drapes) keeps the solver's old order:
        // from_flat_options leaves it off there.
        QCOMPARE(from_flat_options({}, on_fold_branch(s, 5)).late_shift_residual, 0.0);
        QCOMPARE(from_flat_options({}, s).late_shift_residual, kLateShiftResidual);
        QCOMPARE(from_flat_options(off, s).late_shift_residual, -1.0);
        if (shifted.status.newton_iterations == crept.status.newton_iterations)
            QSKIP("the drape met no indefinite exact Hessian near rest on this machine (the path depends on the rounding)");
        QCOMPARE(shifted.metrics.node_count, crept.metrics.node_count);
        QVERIFY(std::abs(shifted.metrics.drape_coefficient_percent - crept.metrics.drape_coefficient_percent) < 0.01);
        QVERIFY(std::abs(shifted.potential_energy - crept.potential_energy) < 1e-6 * std::abs(crept.potential_energy));
        QVERIFY(shifted.status.newton_iterations < crept.status.newton_iterations);
    }

    void fold_mode_starts_on_the_requested_branch()
    {
        // The default fabric at grid 25 drapes from the random mix with 8-9 folds; a
        // 6-fold lift of 5 mm puts it on its (stable) 6-fold branch, with a lower D
        // (fewer, deeper folds). Seeds only move the phase and the small mix.
        FabricParams p;
        p[Param::Shear] = 100;
        DrapeSetup s = small(25, 1);
        s.perturbation = 5e-3;
        const DrapeResult random = simulate_drape(p, s);
        QVERIFY(random.status.converged());
        QVERIFY2(random.metrics.node_count >= 8, qPrintable(QString::number(random.metrics.node_count)));
        for (std::uint64_t seed : {1, 2}) {
            s.seed = seed;
            s.fold_mode = 6;
            const DrapeResult six = simulate_drape(p, s);
            QVERIFY2(six.status.converged(), six.status.message.c_str());
            QCOMPARE(six.metrics.node_count, 6);
            QVERIFY(six.metrics.drape_coefficient_percent < random.metrics.drape_coefficient_percent);
        }
        for (int bad : {1, -3, 17}) {
            s.fold_mode = bad;
            QVERIFY_THROWS_EXCEPTION(drape::ParameterError, s.validate());
        }
    }

    void fold_angle_places_the_crests()
    {
        // DrapeSetup::fold_angle: an n-fold start with one crest at a chosen angle
        // from the warp rests with its crests there (the n-th harmonic of the
        // shadow has its maximum at that angle), whatever the seed; on a fabric
        // 2.5 times stiffer along the warp, six crests with one on the warp (0) and
        // with one on the weft (30 degrees) are two rest states, told apart by their
        // contours' cos 2theta term.
        FabricParams p;
        p[Param::BendWarp] = 1.5e-5;
        p[Param::BendWeft] = 6e-6;
        p[Param::Shear] = 20;
        p[Param::AreaDensity] = 0.18;
        const double kPi = std::numbers::pi;
        double cos2[2] = {0, 0};
        for (int a = 0; a < 2; ++a) {
            const double angle = a == 0 ? 0.0 : kPi / 6;
            double first_dc = 0;
            for (std::uint64_t seed : {1, 2}) {
                const DrapeSetup s = on_fold_branch(small(25, seed), 6, kFoldBranchLift, angle);
                const DrapeResult r = simulate_drape(p, s);
                QVERIFY2(r.status.converged(), r.status.message.c_str());
                QCOMPARE(r.metrics.node_count, 6);
                const FourierSeries f = fourier_fit(r.metrics.profile, 8);
                const double crest = std::atan2(f.b[5], f.a[5]) / 6; // the 6th harmonic's maximum
                double off = std::remainder(crest - angle, kPi / 3);
                QVERIFY2(std::abs(off) < 0.1, qPrintable(QString("crest %1 rad against %2").arg(crest).arg(angle)));
                if (seed == 1) first_dc = r.metrics.drape_coefficient_percent;
                else QVERIFY(std::abs(r.metrics.drape_coefficient_percent - first_dc) < 0.5); // the seed only moves the small mix
                for (const Slice& sl : r.slices) // the contour 20 mm below the pedestal top
                    if (std::abs(sl.depth_m - 0.02) < 1e-9 && sl.profile.complete()) cos2[a] += fourier_fit(sl.profile, 8).a[1] / 2;
            }
        }
        qInfo("cos 2theta at 20 mm: a crest on the warp %.2f mm, on the weft %.2f mm", cos2[0] * 1e3, cos2[1] * 1e3);
        QVERIFY(std::abs(cos2[0] - cos2[1]) > 1e-3);
        DrapeSetup bad = small();
        bad.fold_mode = 6;
        bad.fold_angle = std::numeric_limits<double>::infinity();
        QVERIFY_THROWS_EXCEPTION(drape::ParameterError, bad.validate());
    }

    void continuation_from_a_kept_level_is_the_same_drape()
    {
        // simulate_drape's `levels` keeps the continuation's level rests a drape
        // passed, and a finer drape of the same fabric and set-up that starts from
        // its coarse level's (`start`) skips that solve and ends where the full
        // continuation ends, bit for bit: a fit's drape from flat at the finer
        // check grid reuses its seed's fit-grid drape (Evaluator::draw_from_flat).
        FabricParams p;
        p[Param::Shear] = 100;
        DrapeSetup coarse = small(kCoarsestLevel, 2);
        coarse.laying_load = 0.4; // the checkpoint is the whole load's, the laying's work counted
        coarse.perturbation = 6e-3;
        std::vector<LevelRest> levels;
        const DrapeResult c = simulate_drape(p, coarse, {}, {}, nullptr, &levels);
        QVERIFY2(c.status.converged(), c.status.message.c_str());
        QVERIFY(c.x == simulate_drape(p, coarse).x); // keeping the level changes nothing
        QCOMPARE(levels.size(), std::size_t{1});
        const LevelRest& kept = levels.front();
        QCOMPARE(kept.grid, kCoarsestLevel);
        QCOMPARE(kept.residual, kLevelResidual);
        QVERIFY(kept.status.converged());
        QVERIFY(kept.status.residual < kLevelResidual && kept.status.residual > c.status.residual);
        QVERIFY(kept.status.newton_iterations > 0 && kept.status.newton_iterations < c.status.newton_iterations);
        QCOMPARE(continuation_level(45), kCoarsestLevel);
        QCOMPARE(continuation_level(kCoarsestLevel), 0);
        QCOMPARE(continuation_level(81), kCoarsestLevel);
        QCOMPARE(continuation_level(82), 81);
        QCOMPARE(continuation_level(161), 81);

        DrapeSetup fine = coarse;
        fine.grid = 45;
        std::vector<LevelRest> none;
        const DrapeResult reused = simulate_drape(p, fine, {}, {}, &kept, &none);
        QVERIFY(none.empty()); // the grid-41 level was not solved again (45 is not a level)
        const DrapeResult full = simulate_drape(p, fine);
        QVERIFY2(full.status.converged(), full.status.message.c_str());
        QVERIFY(reused.x == full.x);
        QCOMPARE(reused.metrics.drape_coefficient_percent, full.metrics.drape_coefficient_percent);
        QCOMPARE(reused.status.newton_iterations, full.status.newton_iterations); // the path's work, the kept level's included
        QCOMPARE(reused.potential_energy, full.potential_energy);
    }

    void laying_under_part_of_the_load_first()
    {
        // DrapeSetup::laying_load: the sheet first rests under a fraction of
        // gravity, then under all of it. The end state is a rest state of the
        // whole load (the residual is the full problem's), 1 is the load at once
        // bit for bit, and the lighter first load buckles the overhang into
        // fewer folds (the mechanism docs/decisions/0013-laying-0-4.md measures
        // on set-a; here 8 -> 6 folds for the cotton starter at grid 41).
        FabricParams p;
        p[Param::Shear] = 100;
        DrapeSetup s = small(25, 1);
        const DrapeResult at_once = simulate_drape(p, s);
        s.laying_load = 1.0;
        const DrapeResult one = simulate_drape(p, s);
        QVERIFY(one.x == at_once.x);
        s.laying_load = 0.3;
        const DrapeResult laid = simulate_drape(p, s);
        QVERIFY2(laid.status.converged(), laid.status.message.c_str());
        QVERIFY(laid.status.residual < 1e-6);
        QVERIFY(laid.status.newton_iterations > 0);
        qInfo("at once: D %.2f %%, %d folds; laid under 0.3 g first: D %.2f %%, %d folds", at_once.metrics.drape_coefficient_percent,
              at_once.metrics.node_count, laid.metrics.drape_coefficient_percent, laid.metrics.node_count);
        QVERIFY2(laid.metrics.node_count < at_once.metrics.node_count,
                 qPrintable(QString("%1 folds laid, %2 at once").arg(laid.metrics.node_count).arg(at_once.metrics.node_count)));
        // Fewer, wider folds hang lower: D goes down with them.
        QVERIFY(laid.metrics.drape_coefficient_percent < at_once.metrics.drape_coefficient_percent);
        for (double bad : {0.0, -0.3, 1.5, std::nan("")}) {
            s.laying_load = bad;
            QVERIFY_THROWS_EXCEPTION(drape::ParameterError, s.validate());
        }
    }

    void specimen_offset_and_weight_gradient_set_up()
    {
        // A specimen laid off centre: its centre held there, the sheet laid there.
        DrapeSetup s = small(25);
        s.specimen_offset = Eigen::Vector2d(4e-3, -2e-3);
        const auto off = make_drape_system(Material(FabricParams()), s);
        const auto ref = make_drape_system(Material(FabricParams()), small(25));
        QCOMPARE(off->model().anchors.front().target.x(), ref->model().anchors.front().target.x() + 4e-3);
        QCOMPARE(off->model().anchors.front().target.y(), ref->model().anchors.front().target.y() - 2e-3);
        QVERIFY((off->x.leftCols(2).colwise().mean() - ref->x.leftCols(2).colwise().mean() - Eigen::RowVector2d(4e-3, -2e-3)).norm() < 1e-12);
        // A weight gradient: the weight is the same, its centre moves towards +y
        // by g R1 <y^2> / R1 (a quarter of the radius times g for a uniform disc).
        s = small(25);
        s.density_gradient = Eigen::Vector2d(0, 0.4);
        const auto grad = make_drape_system(Material(FabricParams()), s);
        const double m = ref->model().total_mass();
        QVERIFY(std::abs(grad->model().total_mass() - m) < 1e-12 * m);
        const double cy = grad->model().mass.dot(grad->x.col(1)) / m;
        QVERIFY2(std::abs(cy - 0.4 * 0.15 / 4) < 0.1 * 0.4 * 0.15 / 4, qPrintable(QString::number(cy)));
    }

    void bad_setups_are_refused()
    {
        DrapeSetup s = small();
        s.sample_diameter = 0.1; // smaller than the disc
        QVERIFY_THROWS_EXCEPTION(drape::ParameterError, make_drape_system(FabricParams(), s));
        s = small();
        s.disc_diameter = -0.15;
        QVERIFY_THROWS_EXCEPTION(drape::ParameterError, make_drape_system(FabricParams(), s));
        s = small(3);
        QVERIFY_THROWS_EXCEPTION(drape::ParameterError, make_drape_system(FabricParams(), s));
        FabricParams p;
        p[Param::AreaDensity] = std::nan("");
        QVERIFY_THROWS_EXCEPTION(drape::ParameterError, make_drape_system(p, small()));
        s = small();
        s.specimen_offset = Eigen::Vector2d(0.08, 0); // off the 75 mm disc
        QVERIFY_THROWS_EXCEPTION(drape::ParameterError, make_drape_system(FabricParams(), s));
        s = small();
        s.density_gradient = Eigen::Vector2d(0.6, 0.8); // the density would reach 0 at the edge
        QVERIFY_THROWS_EXCEPTION(drape::ParameterError, make_drape_system(FabricParams(), s));
        // A seed preset describes its own sheet size.
        s = small();
        s.sample_diameter = 0.36;
        QVERIFY_THROWS_EXCEPTION(drape::ParameterError, make_drape_system(Material(FabricParams(), GridSprings{}), s));
        // Grid springs need the grid mesh; an unknown mesh name is named.
        s = small();
        s.mesh = DrapeMesh::Rings;
        try {
            make_drape_system(Material(FabricParams(), GridSprings{}), s);
            QFAIL("grid springs on rings were accepted");
        } catch (const drape::ParameterError& e) {
            QVERIFY2(std::string(e.what()).find("need the grid mesh") != std::string::npos, e.what());
        }
        s = small();
        s.mesh = DrapeMesh::Rings;
        s.grid = kMinRingsGrid - 1;
        QVERIFY_THROWS_EXCEPTION(drape::ParameterError, s.validate());
        ModelOptions arcs;
        arcs.arc_membrane = true;
        try {
            make_drape_system(FabricParams(), small(), arcs); // the grid takes arcs
            make_drape_system(FabricParams(), [] { DrapeSetup r = small(); r.mesh = DrapeMesh::Rings; return r; }(), arcs);
            QFAIL("arcs on rings were accepted");
        } catch (const drape::ParameterError& e) {
            QVERIFY2(std::string(e.what()).find("arc") != std::string::npos, e.what());
        }
        try {
            drape_mesh_from_string("hex");
            QFAIL("an unknown mesh was accepted");
        } catch (const drape::ParameterError& e) {
            QVERIFY2(std::string(e.what()).find("\"hex\"") != std::string::npos, e.what());
        }
    }

    void cancellation_stops_the_solver()
    {
        std::atomic<bool> cancel{true};
        RestOptions ro;
        ro.cancel = &cancel;
        auto sys = make_drape_system(FabricParams(), small());
        const SolverStatus st = run_to_rest(*sys, ro);
        QCOMPARE(st.outcome, SolverStatus::Outcome::Cancelled);
    }
};

QTEST_APPLESS_MAIN(TestDrape)
#include "tst_drape.moc"
