// Fit round trip on a small grid (unit): a record simulated with known
// parameters is fitted; the parameters the drape constrains come back inside
// their reported intervals, dampers are reported as not identifiable, and the
// same seed gives the same fit.
#include "engine/core/error.hpp"
#include "engine/estimate/fit.hpp"
#include "engine/estimate/detail/stages.hpp"
#include "synthetic.hpp"

#include <QTest>

#include <cmath>

using namespace drape;
using namespace drape::estimate;
using cloth::Param;

namespace {
cloth::FabricParams truth()
{
    cloth::FabricParams p;
    p[Param::BendWarp] = 2.0e-5;
    p[Param::BendWeft] = 8.0e-6;
    p[Param::Shear] = 20;
    p[Param::AreaDensity] = 0.2;
    return p;
}

MeasuredDrape synthetic(const cloth::FabricParams& p, double D1, double D2, int grid, std::uint64_t seed)
{
    return test::synthetic_record(p, test::drape_setup(D1, D2, grid, seed));
}

/// The calibration from flat's tests: grid 25, its drapes from flat also on grid
/// 33, warp and weft free, no effect tests, the calibration on.
FitOptions calibration_options()
{
    FitOptions o;
    o.grid = 25;
    o.seed = 1;
    o.flat_check_grid = 33;
    o.bending = BendingTie::Free;
    o.effects = false;
    o.flat_calibration = true;
    return o;
}

const ParamEstimate& est(const FitResult& r, Param p)
{
    for (const auto& e : r.estimates)
        if (e.id == p) return e;
    throw std::logic_error("missing estimate");
}
} // namespace

class TestFit : public QObject {
    Q_OBJECT
private slots:
    void roundTripSmallGrid()
    {
        const auto p = truth();
        const MeasuredDrape rec = synthetic(p, 0.30, 0.15, 17, 7);
        QVERIFY(rec.contours.size() >= 3);
        FitOptions o;
        o.grid = 17;
        o.seed = 1;
        o.seeds_per_evaluation = 1;
        o.scan_evaluations = 6;
        o.global_evaluations = 4;
        o.local_evaluations = 20; // BOBYQA spends 2n + 1 = 7 on its first model
        o.flat_check_grid = 25;
        // Progress: the search's stages first, then the drapes after it, each
        // announced before its drapes run (a display has something to say during
        // them) and marked as after the search (no evaluations to count there).
        std::vector<FitProgress> seen;
        o.progress = [&](const FitProgress& fp) { seen.push_back(fp); };
        const FitResult r = fit_fabric({rec}, o);
        QVERIFY(!r.cancelled);
        QVERIFY(r.simulations > 0 && r.seconds_per_simulation() > 0);
        {
            QVERIFY(seen.size() > 3);
            QCOMPARE(seen.back().stage, std::string("done"));
            std::size_t first_after = seen.size();
            for (std::size_t k = 0; k < seen.size(); ++k)
                if (!seen[k].search) {
                    first_after = k;
                    break;
                }
            QVERIFY(first_after > 0 && first_after < seen.size());
            const std::string& st = seen[first_after].stage; // "from flat", or "tie from flat" when the tied refit is kept
            QVERIFY2(st.size() >= 9 && st.compare(st.size() - 9, 9, "from flat") == 0, st.c_str());
            QVERIFY(seen[first_after].starting);
            QVERIFY(seen[first_after].simulations < r.simulations); // announced before its drapes
            for (std::size_t k = 0; k < seen.size(); ++k) {
                QVERIFY2(seen[k].search == (k < first_after), seen[k].stage.c_str());
                QVERIFY(seen[k].evaluation <= seen[k].planned);
                if (k > 0) QVERIFY(seen[k].simulations >= seen[k - 1].simulations);
            }
            const std::string line = fit_progress_line(seen[first_after]);
            qInfo("%s", line.c_str());
            QVERIFY2(line.find("the preset from flat on the fit's grid") != std::string::npos && line.find(" simulations") != std::string::npos, line.c_str());
            QVERIFY(fit_progress_line(seen[first_after - 1]).find("evaluation") != std::string::npos);
            bool effects = false;
            for (const auto& fp : seen) effects = effects || (fp.stage_id == estimate::Stage::Effects && fp.starting);
            QVERIFY(effects);
        }
        // The fit's cold drapes start on the record's measured fold branch; the
        // preset draped from the random mix (as `drape predict`) is reported beside.
        QCOMPARE(r.records[0].branch_folds, static_cast<int>(std::lround(r.records[0].measured_features.node_count)));
        QCOMPARE(r.records[0].setup.fold_mode, r.records[0].branch_folds);
        QCOMPARE(r.records[0].cold_seeds, o.random_start_seeds);
        QVERIFY(std::isfinite(r.records[0].cold_dc_error_percent) && r.records[0].cold_features.drape_coefficient_percent > 0);
        QVERIFY(std::abs(r.records[0].cold_dc_error_percent - (r.records[0].cold_features.drape_coefficient_percent -
                                                               r.records[0].measured_features.drape_coefficient_percent)) < 1e-12);
        // And its first seed from flat on the finer check grid: the drape `drape
        // simulate --grid 25` gives the preset (same seed, same laying).
        const RecordFit& rf = r.records[0];
        QCOMPARE(rf.cold_fine_grid, 25);
        cloth::DrapeSetup fine = rec.setup(25, o.seed + 1000);
        fine.laying_load = o.laying_load;
        const cloth::DrapeResult direct = cloth::simulate_drape(r.params, fine, o.rest, o.model_options);
        qInfo("from flat: grid 17 %.2f %% (%.1f nodes), grid 25 %.2f %% (%.0f nodes), direct %.2f %%", rf.cold_features.drape_coefficient_percent,
              rf.cold_features.node_count, rf.cold_fine_features.drape_coefficient_percent, rf.cold_fine_features.node_count,
              direct.metrics.drape_coefficient_percent);
        QVERIFY(std::abs(rf.cold_fine_features.drape_coefficient_percent - direct.metrics.drape_coefficient_percent) < 1e-9);
        QVERIFY(rf.cold_fine_converged); // so it is one of the drapes the calibration averaged
        // Every drape from flat within one fold of the record (the stage's condition).
        QVERIFY(std::abs(rf.cold_fine_features.node_count - rf.measured_features.node_count) <= 1);
        QVERIFY(direct.status.converged());
        QCOMPARE(rf.cold_fine_converged, direct.status.converged());
        QCOMPARE(rf.cold_fine_features.node_count, static_cast<double>(direct.metrics.node_count));
        QVERIFY(std::abs(rf.cold_fine_dc_error_percent - (rf.cold_fine_features.drape_coefficient_percent - rf.measured_features.drape_coefficient_percent)) <
                1e-12);
        // The exact sensitivity of D to each fitted parameter at the optimum: one
        // entry per fitted parameter, stiffer bending drapes higher.
        QCOMPARE(r.records[0].d_drape_per_10_percent.size(), r.variables.size());
        for (const auto& [q, d] : r.records[0].d_drape_per_10_percent) {
            qInfo("dD for +10 %% of %s: %+.3f points", std::string(cloth::spec(q).key).c_str(), d);
            QVERIFY(std::isfinite(d));
            if (q == Param::BendWarp || q == Param::BendWeft) QVERIFY(d > 0);
        }
        // What one small-grid drape constrains is the overall bending (the
        // mean of log10 warp and weft bending): it is inside its 95 % interval
        // from the fit's covariance. (The warp/weft split of one drape is not
        // reliably recovered yet: see tst_est_fit_slow and docs/estimate.md.)
        int iw = -1, If = -1;
        for (int i = 0; i < static_cast<int>(r.variables.size()); ++i) {
            if (r.variables[i].params.front() == Param::BendWarp) iw = i;
            if (r.variables[i].params.front() == Param::BendWeft) If = i;
        }
        QVERIFY(iw >= 0 && If >= 0);
        const double mean_fit = 0.5 * (r.best_coords[iw] + r.best_coords[If]);
        const double mean_true = 0.5 * (std::log10(p[Param::BendWarp]) + std::log10(p[Param::BendWeft]));
        const double var = 0.25 * (r.covariance(iw, iw) + r.covariance(If, If) + 2 * r.covariance(iw, If));
        qInfo("mean log10 bending: truth %.3f fitted %.3f +- %.3f (95 %%)", mean_true, mean_fit, 1.96 * std::sqrt(std::max(var, 0.0)));
        QVERIFY(std::isfinite(var) && var >= 0);
        QVERIFY(std::abs(mean_fit - mean_true) <= 1.96 * std::sqrt(var));
        for (Param q : {Param::BendWarp, Param::BendWeft}) {
            const auto& e = est(r, q);
            QCOMPARE(e.role, std::string("fitted"));
            qInfo("%s: truth %.3g fitted %.3g [%.3g, %.3g] constrained %d", e.key.c_str(), p[q], e.value, e.lower95, e.upper95,
                  int(e.constrained));
            QVERIFY(e.lower95 <= e.value && e.value <= e.upper95);
        }
        // the fitted drape matches the record's D within the noise the fit reports
        // (at this tiny grid the drape-to-drape spread of D is ~2 points)
        qInfo("D measured %.2f fitted %.2f, nodes %.1f vs %.1f", r.records[0].measured_features.drape_coefficient_percent,
              r.records[0].simulated_features.drape_coefficient_percent, r.records[0].measured_features.node_count,
              r.records[0].simulated_features.node_count);
        for (const auto& t : r.residuals)
            if (t.kind == "dc") {
                qInfo("D sigma %.2f, whitened residual %.2f", t.sigma, t.whitened());
                QVERIFY(std::abs(t.whitened()) < 2.5);
                QVERIFY(std::abs(t.simulated - t.measured) < 4.0);
            }
        // declared and non-identifiable parameters are reported as such
        QCOMPARE(est(r, Param::AreaDensity).role, std::string("declared"));
        QCOMPARE(est(r, Param::AreaDensity).value, rec.areal_density);
        for (Param q : {Param::DampStretch, Param::DampShear, Param::DampBend, Param::DampAir}) {
            QCOMPARE(est(r, q).role, std::string("not identifiable"));
            QVERIFY(!est(r, q).constrained);
        }
        // the preset JSON lists them as not constrained and carries the residual object
        const auto j = fit_to_json(r);
        QVERIFY(j["fit"]["not_constrained"].size() >= 4);
        QVERIFY(j["residual"].contains("exceeds_noise"));
        QVERIFY(j["residual"].contains("dominant_harmonics"));
        QVERIFY(j["residual"].contains("candidate_effects"));
        QVERIFY(j["residual"]["rms_m"].get<double>() >= 0);
    }

    void sensitivityFitKeepsAnIsotropicFabricIsotropic()
    {
        // The default method: Levenberg-Marquardt on the exact rest-state
        // sensitivities. An isotropic fabric (warp = weft bending) at grid 25,
        // where its bending length (17 mm) is above the mesh spacing (12.5 mm).
        cloth::FabricParams p = truth();
        p[Param::BendWarp] = p[Param::BendWeft] = 1.0e-5;
        const MeasuredDrape rec = synthetic(p, 0.30, 0.15, 25, 11);
        FitOptions o;
        o.grid = 25;
        o.seed = 1;
        const FitResult r = fit_fabric({rec}, o);
        QCOMPARE(r.options.method, FitMethod::Sensitivity);
        QVERIFY(!r.cancelled && !r.grid_bound);
        // Sensitivities, not re-solves: one factorisation per linearised drape (two
        // seeds per Jacobian), each serving several back-substitutions (the fitted
        // parameters; the effect tests' parameters); no derivative-free global stage.
        QVERIFY(r.jacobians > 0);
        QVERIFY(r.factorisations >= r.jacobians);
        QVERIFY(r.back_substitutions >= r.factorisations * 2);
        QVERIFY(!r.trace.empty());
        for (const auto& t : r.trace) QVERIFY2(t.stage != "global", "no CRS2 stage by default");
        QCOMPARE(r.trace.back().evaluation, r.evaluations);
        int iw = -1, If = -1;
        for (int i = 0; i < static_cast<int>(r.variables.size()); ++i) {
            if (r.variables[i].params.front() == Param::BendWarp) iw = i;
            if (r.variables[i].params.front() == Param::BendWeft) If = i;
        }
        // warp - weft in decades against its own 95 % interval (the fit's covariance)
        const double diff = r.best_coords[iw] - r.best_coords[If];
        const double var = r.covariance(iw, iw) + r.covariance(If, If) - 2 * r.covariance(iw, If);
        qInfo("log10 warp/weft bending: %+.3f +- %.3f (95 %%), %d evaluations, %ld drapes, %ld factorisations, chi2 %.1f / %d", diff,
              1.96 * std::sqrt(std::max(var, 0.0)), r.evaluations, r.simulations, r.factorisations, r.chi2, r.dof);
        QVERIFY(std::isfinite(var) && var > 0);
        QVERIFY2(std::abs(diff) <= 1.96 * std::sqrt(var), "an isotropic fabric fitted as anisotropic beyond its interval");
        // and the common bending comes back within its interval
        const double mean_fit = 0.5 * (r.best_coords[iw] + r.best_coords[If]);
        const double var_mean = 0.25 * (r.covariance(iw, iw) + r.covariance(If, If) + 2 * r.covariance(iw, If));
        QVERIFY(std::abs(mean_fit - std::log10(1.0e-5)) <= 1.96 * std::sqrt(var_mean));
        QVERIFY(!r.residual.exceeds_noise);
        // The preset JSON carries the method, the counts and the trace.
        const auto j = fit_to_json(r);
        QCOMPARE(j["fit"]["method"].get<std::string>(), std::string("lm"));
        QCOMPARE(j["fit"]["trace"].size(), r.trace.size());
        QCOMPARE(j["fit"]["factorisations"].get<long>(), r.factorisations);
        QCOMPARE(j["fit"]["jacobian_jumps"].get<long>(), r.jacobian_jumps);
        // The warp/weft assessment agrees with the interval above: not separated,
        // the ratio's 95 % interval holds 1; a tied refit only beyond the typical factor.
        QVERIFY(r.anisotropy.assessed);
        QVERIFY(!r.anisotropy.separated);
        QVERIFY(r.anisotropy.ratio_lower95 <= 1 && r.anisotropy.ratio_upper95 >= 1);
        QCOMPARE(r.anisotropy.refit, std::max(r.anisotropy.ratio, 1 / r.anisotropy.ratio) > kTypicalBendingAnisotropy);
        QCOMPARE(j["fit"]["bending"].get<std::string>(), std::string("auto"));
        QCOMPARE(j["fit"]["bending_anisotropy"]["separated"].get<bool>(), false);
    }

    void flatCalibrationPutsTheDrapeFromFlatOnTheRecordsD()
    {
        // A record whose drapemeter D reads 5 points above what its own contours'
        // fabric drapes to (the model's D and contours disagree, as on lab records):
        // the contours' optimum, draped from flat, misses the record's D; the
        // calibration scales both bendings up by one factor until the preset's
        // drapes from flat (the report's cold_*, both grids) give the record's D,
        // keeping the warp/weft ratio, and says what that costs the contours.
        cloth::FabricParams p = truth();
        p[Param::BendWarp] = p[Param::BendWeft] = 1.0e-5;
        MeasuredDrape rec = synthetic(p, 0.30, 0.15, 25, 11);
        rec.drape_coefficient_percent += 5.0;
        FitOptions o = calibration_options();
        const FitResult r = fit_fabric({rec}, o);
        QVERIFY(!r.cancelled);
        const auto& c = r.flat_calibration;
        const RecordFit& rf = r.records[0];
        qInfo("from flat: %s; grid 25 %.2f %% (%.1f folds), grid 33 %.2f %% (%.0f folds), measured %.2f %% (%.0f folds)", c.reason.c_str(),
              rf.cold_features.drape_coefficient_percent, rf.cold_features.node_count, rf.cold_fine_features.drape_coefficient_percent,
              rf.cold_fine_features.node_count, rf.measured_features.drape_coefficient_percent, rf.measured_features.node_count);
        QVERIFY(c.tried);
        QVERIFY2(c.error_before < -c.tolerance, "the contours' optimum drapes below the raised D");
        QVERIFY(c.applied);
        QVERIFY(c.scale > 1.0 && c.scale <= 1.5 + 1e-12);
        QVERIFY(std::abs(c.error_after) < std::abs(c.error_before));
        QVERIFY(c.steps >= 1 && c.steps <= 2);
        QCOMPARE(c.history.size(), static_cast<std::size_t>(c.steps));
        QVERIFY(std::isfinite(c.chi2_increase)); // linearised at an optimum that is not exact: no sign asserted
        // The preset is the contours' optimum times the scale, the ratio kept, and
        // the bending estimates say so.
        QVERIFY(std::abs(r.params[Param::BendWarp] / c.bend_warp_fitted - c.scale) < 1e-9 * c.scale);
        QVERIFY(std::abs(r.params[Param::BendWeft] / c.bend_weft_fitted - c.scale) < 1e-9 * c.scale);
        QCOMPARE(est(r, Param::BendWarp).value, r.params[Param::BendWarp]);
        QVERIFY(est(r, Param::BendWarp).note.find("scaled by") != std::string::npos);
        // The records' drapes from flat are the calibrated preset's: the finer grid's
        // is the drape `drape simulate --grid 33` gives the preset (same seed, laying).
        cloth::DrapeSetup fine = rec.setup(33, o.seed + 1000);
        fine.laying_load = o.laying_load;
        const cloth::DrapeResult direct = cloth::simulate_drape(r.params, fine, o.rest, o.model_options);
        QVERIFY(std::abs(rf.cold_fine_features.drape_coefficient_percent - direct.metrics.drape_coefficient_percent) < 1e-9);
        const double mean_flat = (rf.cold_seeds * rf.cold_features.drape_coefficient_percent + rf.cold_fine_features.drape_coefficient_percent) /
                                 (rf.cold_seeds + 1);
        QVERIFY(std::abs(mean_flat - rf.measured_features.drape_coefficient_percent - c.error_after) < 1e-9);
        const auto j = fit_to_json(r);
        QCOMPARE(j["fit"]["flat_calibration"]["applied"].get<bool>(), true);
        QCOMPARE(j["fit"]["flat_calibration"]["scale"].get<double>(), c.scale);
        // A fit from the random mix has no fold branch to hold the drapes from flat
        // to: the stage is not tried (its grid-41 drapes are the spread stage's, of
        // the optimum, and would not follow a scale).
        {
            FitOptions rnd = o;
            rnd.branch = FoldBranch::Random;
            const FitResult rr = fit_fabric({rec}, rnd);
            QVERIFY(!rr.flat_calibration.tried && !rr.flat_calibration.applied);
            QVERIFY(rr.flat_calibration.reason.find("fold branch") != std::string::npos);
            QCOMPARE(rr.params[Param::BendWarp], est(rr, Param::BendWarp).value);
        }
        // Off (the library's default): the preset is the contours' optimum.
        o.flat_calibration = false;
        const FitResult off = fit_fabric({rec}, o);
        QVERIFY(!off.flat_calibration.tried);
        QVERIFY(!fit_to_json(off)["fit"].contains("flat_calibration"));
        QCOMPARE(off.params[Param::BendWarp], c.bend_warp_fitted);
        QCOMPARE(off.params[Param::BendWeft], c.bend_weft_fitted);
    }

    void profileFollowsTheBendingWhereTheChi2IsLeast()
    {
        // chi2(b, g, h) = (b - g)^2 + (0.1 g)^2 + (2 h)^2, a masked row 5 b aside: held
        // at b = 1, the chi2 is least at g = 1 / 1.01 and h = 0, where it has risen by
        // 0.01 / 1.01 per unit b^2 - the profile the calibration from flat steps along.
        Eigen::MatrixXd J(4, 3);
        J << 1, -1, 0, //
            0, 0.1, 0, //
            0, 0, 2,   //
            5, 0, 0;
        double curvature = 0;
        const Eigen::VectorXd dir = detail::profile_direction(J, {1, 1, 1, 0}, {0}, curvature);
        QCOMPARE(dir.size(), Eigen::Index(3));
        QCOMPARE(dir[0], 1.0);
        QVERIFY(std::abs(dir[1] - 1 / 1.01) < 1e-12);
        QVERIFY(std::abs(dir[2]) < 1e-12);
        QVERIFY(std::abs(curvature - 0.01 / 1.01) < 1e-12);
        // Two bending coordinates step together; a coordinate no row sees stays.
        Eigen::MatrixXd J2(2, 4);
        J2 << 1, 1, -1, 0, //
            0, 0, 1, 0;
        const Eigen::VectorXd d2 = detail::profile_direction(J2, {1, 1}, {0, 1}, curvature);
        QCOMPARE(d2[0], 1.0);
        QCOMPARE(d2[1], 1.0);
        QVERIFY(std::abs(d2[2] - 1.0) < 1e-12); // min (2 - g)^2 + g^2: g = 1
        QCOMPARE(d2[3], 0.0);
        QVERIFY(std::abs(curvature - 2.0) < 1e-12);
    }

    void flatCalibrationStepsAlongTheProfileForTheFoldCount()
    {
        // A record that states two folds more than its fabric lays from flat: the fit
        // drapes on the stated branch, its preset draped from flat misses the count by
        // 2, and the calibration steps the bendings (softer: too few folds) along the
        // contours' profile, 1 then 2 sigma, screening each step on the fit grid's
        // drapes. Whatever it finds, the result must be consistent: kept only when its
        // drapes from flat are within 1 fold and closer to the record by more than the
        // contours' linearised chi2 rises; else the preset is the contours' optimum.
        // (A stiff anisotropic fabric with a moderate shear, where the contours' profile
        // trades bending for shear: on this machine the step of 1 sigma is kept.)
        cloth::FabricParams p = truth();
        p[Param::BendWarp] = 3.0e-5;
        p[Param::BendWeft] = 1.2e-5;
        p[Param::Shear] = 30;
        MeasuredDrape rec = synthetic(p, 0.30, 0.15, 25, 11);
        FitOptions o = calibration_options();
        o.shear = ShearHold::Free; // the profile's follower is the shear (held, the profile would move the bendings alone)
        {
            // The count the fabric lays from flat (the calibration's first seed), and a
            // photo that "reads" two more.
            cloth::DrapeSetup laid = rec.setup(25, o.seed + 1000);
            laid.laying_load = o.laying_load;
            const cloth::DrapeResult d = cloth::simulate_drape(p, laid, o.rest, o.model_options);
            rec.node_count = static_cast<int>(std::lround(d.metrics.node_count)) + 2;
            rec.node_source = "test";
        }
        const FitResult r = fit_fabric({rec}, o);
        QVERIFY(!r.cancelled);
        const auto& c = r.flat_calibration;
        qInfo("from flat (%s): %s", c.applied ? "applied" : "not applied", c.reason.c_str());
        for (const auto& h : c.history)
            qInfo("  %s: sigmas %.0f, bendings x %.3f, D %+.2f, folds %.0f off, chi2 %+.1f%s", h.kind.c_str(), h.sigmas, h.scale, h.error, h.fold_error,
                  h.chi2_cost, h.finer_grid ? " (with the finer grid)" : "");
        QVERIFY(c.tried);
        // The precondition is one bifurcation at the fitted optimum (docs/decisions/0027-portable-blas-kernels.md:
        // such outcomes can differ with the machine's rounding): without it there
        // is no search to check.
        if (!(c.fold_error_before > 1)) QSKIP("the preset's drapes from flat lay the stated count within 1 here: no fold search");
        QVERIFY(c.fold_search);
        if (c.fold_direction == 0) QSKIP("no profile to step along here (see the reason)");
        QCOMPARE(c.fold_direction, -1.0); // too few folds: softer
        int fold_steps = 0;
        for (const auto& h : c.history)
            if (h.kind == "fold count") {
                ++fold_steps;
                QVERIFY(!h.finer_grid);
                QVERIFY(h.sigmas > 0 && h.sigmas <= 2 + 1e-12); // 1 then 2, or less where the box shortened it
                QVERIFY(h.scale < 1); // softer bendings
                QVERIFY(std::isfinite(h.chi2_cost));
            }
        QVERIFY(fold_steps >= 1 && fold_steps <= 2);
        const double ratio = r.params[Param::BendWarp] / r.params[Param::BendWeft];
        QVERIFY(std::abs(ratio / (c.bend_warp_fitted / c.bend_weft_fitted) - 1) < 1e-9); // warp/weft ratio kept
        const double node_sigma = 0.75;
        auto score = [&](double e, double f) { return (e / c.tolerance) * (e / c.tolerance) + (f / node_sigma) * (f / node_sigma); };
        if (c.applied) {
            QVERIFY(c.fold_error_after <= 1);
            QVERIFY(c.fold_sigmas > 0 && c.fold_sigmas <= 2 + 1e-12);
            QVERIFY(std::isfinite(c.chi2_increase));
            const double s2 = std::max(1.0, r.chi2 / std::max(1, r.dof));
            QVERIFY(c.chi2_increase / s2 < score(c.error_before, c.fold_error_before) - score(c.error_after, c.fold_error_after));
            QVERIFY(c.history.back().kind == "preset" && c.history.back().finer_grid);
            // The preset moved off the optimum (the profile step softened the bendings; a D
            // step after it may scale them either way), and its estimates say how.
            QVERIFY(r.params[Param::BendWarp] != c.bend_warp_fitted);
            QVERIFY(!c.moved.empty());
            QCOMPARE(est(r, Param::BendWarp).value, r.params[Param::BendWarp]);
            QVERIFY(est(r, Param::BendWarp).note.find("profile") != std::string::npos);
            QCOMPARE(est(r, Param::Shear).value, r.params[Param::Shear]);
            // The report's drapes from flat are the calibrated preset's.
            const RecordFit& rf = r.records[0];
            cloth::DrapeSetup fine = rec.setup(33, o.seed + 1000);
            fine.laying_load = o.laying_load;
            const cloth::DrapeResult direct = cloth::simulate_drape(r.params, fine, o.rest, o.model_options);
            QVERIFY(std::abs(rf.cold_fine_features.drape_coefficient_percent - direct.metrics.drape_coefficient_percent) < 1e-9);
        } else {
            QVERIFY(c.fold_search_failed);
            QCOMPARE(c.fold_sigmas, 0.0);
            QVERIFY(c.moved.empty());
            QVERIFY(c.reason.find("not calibrated") != std::string::npos);
            QCOMPARE(r.params[Param::BendWarp], c.bend_warp_fitted);
            QCOMPARE(r.params[Param::BendWarp], est(r, Param::BendWarp).value);
            QCOMPARE(r.params[Param::Shear], est(r, Param::Shear).value);
        }
        const auto j = fit_to_json(r);
        QCOMPARE(j["fit"]["flat_calibration"]["fold_search"].get<bool>(), true);
        QCOMPARE(j["fit"]["flat_calibration"]["steps_tried"].size(), c.history.size());
    }

    void untypicalUnseparatedAnisotropyIsTied()
    {
        // The same isotropic record as above with the typical factor set to 1: any
        // free ratio is then "beyond it", the free fit cannot separate warp from weft,
        // so the tied refit runs and - the data not needing anisotropy - is kept.
        cloth::FabricParams p = truth();
        p[Param::BendWarp] = p[Param::BendWeft] = 1.0e-5;
        const MeasuredDrape rec = synthetic(p, 0.30, 0.15, 25, 11);
        FitOptions o;
        o.grid = 25;
        o.typical_bending_anisotropy = 1.0;
        o.effects = false;
        o.random_start_seeds = 0; // (the spread calibration stays: the test's chi2 are in its sigmas)
        const FitResult r = fit_fabric({rec}, o);
        qInfo("%s", r.anisotropy.reason.c_str());
        QVERIFY(r.anisotropy.assessed && !r.anisotropy.separated);
        QVERIFY(r.anisotropy.refit);
        QVERIFY(r.anisotropy.tied);
        QVERIFY(r.anisotropy.delta_chi2 < 9.0);
        QCOMPARE(r.params[Param::BendWarp], r.params[Param::BendWeft]);
        // The tied refit keeps the free fit's shear decision: a held shear stays held
        // (not a coordinate: bend_Nm alone), a kept one is fitted again.
        qInfo("shear: %s", r.shear_hold.reason.c_str());
        QCOMPARE(r.variables.size(), std::size_t(r.shear_hold.held ? 1 : 2));
        if (r.shear_hold.held) {
            QCOMPARE(r.params[Param::Shear], r.shear_hold.held_N_m);
            QCOMPARE(est(r, Param::Shear).role, std::string("held"));
        }
        QCOMPARE(r.options.shear, ShearHold::Auto);
        QCOMPARE(r.chi2, r.anisotropy.tied_chi2);
        // Counts and trace hold both fits, the tied one's stages prefixed.
        bool tie_stage = false;
        for (const auto& t : r.trace) tie_stage = tie_stage || t.stage.rfind("tie ", 0) == 0;
        QVERIFY(tie_stage);
        QCOMPARE(r.trace.back().evaluation, r.evaluations);
        const auto j = fit_to_json(r);
        QCOMPARE(j["fit"]["bending_anisotropy"]["tied"].get<bool>(), true);
    }

    void unconstrainedShearIsHeldAtTheTypicalValue()
    {
        // D alone cannot tell the shear (one term for three coordinates: the Jacobian
        // has a null direction), so ShearHold::Auto moves it to the typical woven value,
        // refits the bendings with it held (the pinned coordinate out of the
        // Levenberg-Marquardt step: the bendings must take D back over), and keeps it
        // there unless chi2 rises by more than 9; the report says which and why. (The
        // truth's and the start's shear, 300 N/m, is far from the typical 56.2 N/m.)
        cloth::FabricParams p = truth();
        p[Param::Shear] = 300;
        const MeasuredDrape rec = synthetic(p, 0.30, 0.15, 17, 3);
        FitOptions o;
        o.grid = 17;
        o.channels = {"dc"};
        o.scan_evaluations = 3;
        o.local_evaluations = 6;
        o.effects = true; // the effect library's shear test says it is held
        o.spread_seeds = 0;
        o.random_start_seeds = 0;
        o.start = p; // starts at the truth's shear: only the hold moves it
        // Warp and weft apart, no tie test: with D alone their ratio is whatever the
        // search leaves (3.42 on one machine, below 3 on another), and beyond 3 the
        // tied refit became the result, whose chi2 is not the held refit's.
        o.bending = BendingTie::Free;
        const FitResult r = fit_fabric({rec}, o);
        QVERIFY(!r.cancelled);
        const auto& h = r.shear_hold;
        qInfo("%s; D error %+.2f", h.reason.c_str(), r.records[0].dc_error_percent);
        QVERIFY(h.assessed);
        QVERIFY(!h.constrained);
        QVERIFY(h.tried);
        QVERIFY(h.held); // D alone: the bendings refit D at any shear
        QVERIFY(std::abs(r.params[Param::Shear] / kTypicalShearNm - 1) < 1e-9);
        // The held refit moved the bendings back onto the record's D (D's sigma is
        // about 1.3 points here; the shear's move alone left D 1.2 sigma off).
        QVERIFY(std::abs(r.records[0].dc_error_percent) < 0.5);
        QVERIFY(h.held_chi2 < 0.5);
        QCOMPARE(r.chi2, h.held_chi2);
        const auto& e = est(r, Param::Shear);
        QCOMPARE(e.role, std::string("held"));
        QVERIFY(!e.constrained);
        QVERIFY(e.note.find("held at the typical") != std::string::npos);
        bool named = false;
        for (const auto& c : r.residual.candidates)
            if (c.name == "shear_stiffness") {
                qInfo("shear_stiffness: %s - %s", c.verdict.c_str(), c.note.c_str());
                named = c.verdict == "not testable" && c.note.find("held at the typical value") != std::string::npos;
            }
        QVERIFY(named);
        const auto j = fit_to_json(r);
        QCOMPARE(j["fit"]["shear_hold"]["held"].get<bool>(), true);
        QCOMPARE(j["fit"]["shear_hold"]["mode"].get<std::string>(), std::string("auto"));
        // Free: the fitted value stays, whatever the data say.
        FitOptions f = o;
        f.shear = ShearHold::Free;
        const FitResult rf = fit_fabric({rec}, f);
        QVERIFY(!rf.shear_hold.assessed);
        QCOMPARE(est(rf, Param::Shear).role, std::string("fitted"));
        QVERIFY(!fit_to_json(rf)["fit"].contains("shear_hold"));
        QCOMPARE(parse_shear_hold("free"), ShearHold::Free);
        QVERIFY_THROWS_EXCEPTION(ParameterError, parse_shear_hold("held"));
        FitOptions bad = o;
        bad.typical_shear_N_m = 0;
        QVERIFY_THROWS_EXCEPTION(ParameterError, fit_fabric({rec}, bad));
    }

    void tiedBendingIsOneCoordinate()
    {
        // --bending tied: one coordinate sets warp and weft; the preset is isotropic
        // and reports it (a small budget: the decade is all this checks).
        const MeasuredDrape rec = synthetic(truth(), 0.30, 0.15, 17, 3);
        FitOptions o;
        o.grid = 17;
        o.bending = BendingTie::Tied;
        o.scan_evaluations = 2;
        o.local_evaluations = 2;
        o.uncertainty = false;
        o.effects = false;
        o.spread_seeds = 0;
        o.random_start_seeds = 0;
        const FitResult r = fit_fabric({rec}, o);
        QCOMPARE(r.variables.size(), std::size_t(2));
        QCOMPARE(r.variables.front().name, std::string("bend_Nm"));
        QCOMPARE(r.variables.front().params.size(), std::size_t(2));
        QCOMPARE(r.params[Param::BendWarp], r.params[Param::BendWeft]);
        QVERIFY(!r.anisotropy.assessed);
        QCOMPARE(fit_to_json(r)["fit"]["bending"].get<std::string>(), std::string("tied"));
        QCOMPARE(parse_bending_tie("free"), BendingTie::Free);
        QVERIFY_THROWS_EXCEPTION(ParameterError, parse_bending_tie("isotropic"));
    }

    void sameSeedSameFit()
    {
        const MeasuredDrape rec = synthetic(truth(), 0.30, 0.15, 17, 3);
        FitOptions o;
        o.grid = 17;
        o.seed = 4;
        o.seeds_per_evaluation = 2;
        o.scan_evaluations = 2;
        o.global_evaluations = 3;
        o.local_evaluations = 3;
        o.uncertainty = false;
        const FitResult a = fit_fabric({rec}, o);
        const FitResult b = fit_fabric({rec}, o);
        QCOMPARE(a.evaluations, b.evaluations);
        QCOMPARE(a.chi2, b.chi2);
        for (int i = 0; i < a.best_coords.size(); ++i) QCOMPARE(a.best_coords[i], b.best_coords[i]);
    }

    void cancellationKeepsBestSoFar()
    {
        const MeasuredDrape rec = synthetic(truth(), 0.30, 0.15, 15, 2);
        std::atomic<bool> cancel{false};
        FitOptions o;
        o.grid = 15;
        o.seeds_per_evaluation = 1;
        o.cancel = &cancel;
        int calls = 0;
        o.progress = [&](const FitProgress& p) {
            QVERIFY(p.evaluation <= p.planned || p.stage_id == estimate::Stage::Done);
            if (++calls == 3) cancel = true;
        };
        const FitResult r = fit_fabric({rec}, o);
        QVERIFY(r.cancelled);
        QVERIFY(r.evaluations >= 3 && r.evaluations <= 4);
        QVERIFY(std::isfinite(r.chi2));
    }

    void gridBoundFitIsRefined()
    {
        // Grid 13 has 25 mm between nodes; the truth's bending lengths
        // ((B / rho_A g)^(1/3)) are 16-22 mm, so the coarse optimum is grid-bound
        // and the fit is repeated on the finer grid from it. The record's random
        // start is seed 7: since the hem has its bending stencils, seed 5's drape at
        // grid 17 sits on a fold branch the refit's starts do not reach (chi2 99 / 65
        // there), and this test is about the refinement, not the fold branch.
        const MeasuredDrape rec = synthetic(truth(), 0.30, 0.15, 17, 7);
        FitOptions o;
        o.grid = 13;
        o.refine_grid = 17;
        o.seeds_per_evaluation = 1;
        o.scan_evaluations = 3;
        o.global_evaluations = 3;
        o.local_evaluations = 3;
        o.spread_seeds = 0;
        o.uncertainty = false;
        std::vector<std::string> stages;
        // One bar for both runs: the counts go on from the coarse run (the refit's
        // first line once said 3 % after the coarse run's 100 %), the evaluations
        // never exceed the plan, and the fit's one "done" comes last.
        int last_eval = 0, dones = 0;
        bool monotone = true;
        o.progress = [&](const FitProgress& p) {
            if (stages.empty() || stages.back() != p.stage) stages.push_back(p.stage);
            monotone = monotone && p.evaluation >= last_eval && p.evaluation <= p.planned;
            last_eval = p.evaluation;
            dones += p.stage_id == estimate::Stage::Done;
        };
        const FitResult r = fit_fabric({rec}, o);
        QVERIFY(monotone);
        QCOMPARE(dones, 1);
        QCOMPARE(stages.back(), std::string("done"));
        QCOMPARE(last_eval, r.evaluations);
        QCOMPARE(r.refinement.from_grid, 13);
        QCOMPARE(r.refinement.to_grid, 17);
        QVERIFY(r.refinement.coarse_chi2 > 0 && r.refinement.fine_chi2 > 0 && !r.refinement.reason.empty());
        qInfo("%s", r.refinement.reason.c_str());
        // The refit is adopted unless it is beyond the noise where the coarse fit was
        // not; the record was made at grid 17, so the refit explains it.
        QVERIFY(r.refinement.adopted);
        const int kept_grid = 17;
        QCOMPARE(r.options.grid, kept_grid);
        // The bend over the rim, about sqrt(B / T) with T = rho_A g (R^2 - a^2) / (2 a)
        // (6-10 mm for the truth), is narrower than grid 17's 18.75 mm: each bending's
        // note says that D may move with the grid (docs/decisions/0019-drapemeter-mesh.md).
        for (Param q : {Param::BendWarp, Param::BendWeft})
            QVERIFY2(est(r, q).note.find("bend over the pedestal's rim") != std::string::npos, est(r, q).note.c_str());
        QCOMPARE(r.records[0].setup.grid, kept_grid);
        QVERIFY(std::find(stages.begin(), stages.end(), "refine scan") != stages.end());
        const auto j = fit_to_json(r);
        QCOMPARE(j["fit"]["refinement"]["from_grid"].get<int>(), 13);
        QCOMPARE(j["fit"]["refinement"]["adopted"].get<bool>(), r.refinement.adopted);
        QCOMPARE(j["provenance"]["grid"].get<int>(), kept_grid);
        // Cancelled during the refit: the finished coarse fit is kept (not an empty
        // partial refit), marked cancelled.
        std::atomic<bool> cancel{false};
        o.cancel = &cancel;
        o.progress = [&](const FitProgress& p) {
            if (p.stage.rfind("refine", 0) == 0) cancel = true;
        };
        const FitResult c = fit_fabric({rec}, o);
        QVERIFY(c.cancelled);
        QVERIFY(!c.refinement.adopted);
        QCOMPARE(c.options.grid, 13);
        QCOMPARE(c.records.size(), std::size_t(1));
        QVERIFY(!c.estimates.empty() && c.chi2 > 0);
        o.cancel = nullptr;
        // Off (0) means no refit; a refine grid at or below the grid is refused.
        o.refine_grid = 0;
        o.progress = nullptr;
        QCOMPARE(fit_fabric({rec}, o).refinement.from_grid, 0);
        o.refine_grid = 13;
        QVERIFY_THROWS_EXCEPTION(ParameterError, fit_fabric({rec}, o));
    }

    void priorDecidesWhatTheDataCannotSee()
    {
        // D alone says nothing of warp against weft: with the priors on, the fit's
        // ratio is the prior's (near 1, not wherever the search stopped), the report
        // says the prior decided it, and the bending level - which D pins - is the
        // data's. The prior rows are linear in the log10 coordinates: their Jacobian
        // rows are exact.
        cloth::FabricParams p = truth();
        const MeasuredDrape rec = synthetic(p, 0.30, 0.15, 17, 3);
        FitOptions o;
        o.grid = 17;
        o.channels = {"dc"};
        o.scan_evaluations = 3;
        o.local_evaluations = 6;
        o.effects = false;
        o.spread_seeds = 0;
        o.random_start_seeds = 0;
        o.bending = BendingTie::Free;
        o.shear = ShearHold::Free;
        o.shear_held_N_m = p[Param::Shear]; // D alone cannot tell the bending level from the shear: the shear is held
        o.priors = true;
        cloth::FabricParams start = p;
        start[Param::BendWarp] = 6e-5; // 7.5 times the weft: the prior must pull it back
        start[Param::BendWeft] = 8e-6;
        o.start = start;
        const FitResult r = fit_fabric({rec}, o);
        QVERIFY(!r.cancelled);
        QCOMPARE(r.priors.size(), std::size_t(2));
        const auto& an = r.priors[0];
        const auto& lvl = r.priors[1];
        QCOMPARE(an.kind, std::string("prior_anisotropy"));
        QCOMPARE(lvl.kind, std::string("prior_bending"));
        qInfo("ratio %.2f: data sigma %.3g, prior %.2f; level: data sigma %.3g", std::pow(10.0, an.value), an.data_sigma, an.prior_sigma,
              lvl.data_sigma);
        QVERIFY(an.decided_by_prior);
        QVERIFY(!lvl.decided_by_prior);
        QVERIFY(std::abs(an.value) < 2 * o.prior.anisotropy_sigma_decades); // pulled towards 1 from 7.5
        QVERIFY(std::abs(r.records[0].dc_error_percent) < 1.0);
        QVERIFY(est(r, Param::BendWarp).note.find("the prior's, not the data's") != std::string::npos);
        const auto j = fit_to_json(r);
        QVERIFY(j["fit"]["priors_on"].get<bool>());
        QCOMPARE(j["fit"]["priors"].size(), std::size_t(2));
        QVERIFY(j["fit"]["priors"][0]["decided_by_prior"].get<bool>());
        // Off: no prior rows and no report of them.
        o.priors = false;
        o.local_evaluations = 1;
        o.scan_evaluations = 1;
        const FitResult off = fit_fabric({rec}, o);
        QVERIFY(off.priors.empty());
        for (const auto& t : off.residuals) QVERIFY(t.kind.rfind("prior", 0) != 0);
    }

    void oneSetupCannotConfirmARatioBeyondTheTypical()
    {
        // A record of one set-up whose contours separate warp from weft: the ratio is
        // kept only where two set-ups confirm it, so with one set-up (and the typical
        // factor set to 1 to force "beyond") the tied fit is the result whatever its
        // chi2 costs, and the reason says why.
        cloth::FabricParams p = truth(); // warp 2.5 times the weft
        const MeasuredDrape rec = synthetic(p, 0.30, 0.15, 25, 11);
        FitOptions o;
        o.grid = 25;
        o.typical_bending_anisotropy = 1.0;
        o.effects = false;
        o.random_start_seeds = 0;
        o.local_evaluations = 8;
        const FitResult r = fit_fabric({rec}, o);
        qInfo("%s", r.anisotropy.reason.c_str());
        QVERIFY(r.anisotropy.assessed);
        QVERIFY(r.anisotropy.refit);
        QVERIFY(r.anisotropy.tied);
        QCOMPARE(r.params[Param::BendWarp], r.params[Param::BendWeft]);
        if (r.anisotropy.separated) QVERIFY(r.anisotropy.reason.find("cannot confirm") != std::string::npos);
    }

    void badInputThrows()
    {
        QVERIFY_THROWS_EXCEPTION(ParameterError, parse_fit_method("bobyqa"));
        QCOMPARE(parse_fit_method("nlopt"), FitMethod::Nlopt);
        QVERIFY_THROWS_EXCEPTION(ParameterError, fit_fabric({}, FitOptions{}));
        MeasuredDrape empty;
        QVERIFY_THROWS_EXCEPTION(ParameterError, fit_fabric({empty}, FitOptions{}));
    }
};

QTEST_APPLESS_MAIN(TestFit)
#include "tst_fit.moc"
