// The fit's policies alone, on small synthetic results (no drape): the warp/weft
// ratio's interval and the two-set-up rule of the bending tie
// (docs/decisions/0010-bending-tie.md, 0029-priors-from-real-fabrics.md), the held
// shear's row (0024-shear-hold.md), and how the runs of one fit add their work and
// join their traces (fit_runs.cpp).
#include "engine/estimate/detail/pipeline.hpp"
#include "engine/estimate/fit.hpp"
#include "engine/estimate/objective.hpp"
#include "engine/estimate/report.hpp"

#include <QFile>
#include <QTemporaryDir>

#include <QTest>

#include <cmath>
#include <limits>

using namespace drape;
using namespace drape::estimate;
using namespace drape::estimate::detail;
using cloth::Param;

namespace {

/// A free baseline fit at log10 bendings (warp, weft), its covariance diagonal in
/// decades^2 (the bendings' off-diagonal c_wf).
FitResult free_fit(double log_warp, double log_weft, double var, double c_wf = 0.0)
{
    FitResult r;
    r.variables = fit_variables(ModelVariant::Baseline);
    const int n = static_cast<int>(r.variables.size());
    r.best_coords = Eigen::VectorXd::Zero(n);
    r.covariance = Eigen::MatrixXd::Identity(n, n) * var;
    const int w = sole_variable(r.variables, Param::BendWarp), f = sole_variable(r.variables, Param::BendWeft);
    r.best_coords[w] = log_warp;
    r.best_coords[f] = log_weft;
    r.covariance(w, f) = r.covariance(f, w) = c_wf;
    for (Param q : {Param::BendWarp, Param::BendWeft}) {
        ParamEstimate e;
        e.id = q;
        e.role = "fitted";
        e.sigma_coord = std::sqrt(var);
        r.estimates.push_back(e);
    }
    return r;
}

/// report.md of `r` as write_fit_report writes it ("" when it cannot be written or read).
QString report_md(const FitResult& r)
{
    QTemporaryDir dir;
    if (!dir.isValid()) return {};
    write_fit_report(r, dir.path().toStdString());
    QFile f(dir.path() + "/report.md");
    return f.open(QIODevice::ReadOnly) ? QString::fromUtf8(f.readAll()) : QString();
}

} // namespace

class TestPolicies : public QObject {
    Q_OBJECT
private slots:
    void ratioAndItsInterval()
    {
        // warp / weft = 10^0.6 = 3.98; the difference's variance 0.01 + 0.01 - 2 * 0.005 = 0.01.
        FitResult r = free_fit(-4.4, -5.0, 0.01, 0.005);
        assess_anisotropy(r);
        const auto& a = r.anisotropy;
        QVERIFY(a.assessed);
        QVERIFY(std::abs(a.ratio - std::pow(10.0, 0.6)) < 1e-12);
        QVERIFY(std::abs(a.ratio_lower95 - std::pow(10.0, 0.6 - 1.96 * 0.1)) < 1e-12);
        QVERIFY(std::abs(a.ratio_upper95 - std::pow(10.0, 0.6 + 1.96 * 0.1)) < 1e-12);
        QVERIFY(a.separated);
        // The same ratio with a wide interval: not separated from 1.
        FitResult wide = free_fit(-4.4, -5.0, 0.2);
        assess_anisotropy(wide);
        QVERIFY(!wide.anisotropy.separated);
    }

    void aBendingTheDataDoNotSeeIsNotSeparated()
    {
        FitResult r = free_fit(-4.0, -5.0, 1e-4);
        r.estimates.front().sigma_coord = std::numeric_limits<double>::infinity();
        assess_anisotropy(r);
        QVERIFY(r.anisotropy.assessed);
        QVERIFY(!r.anisotropy.separated);
        QCOMPARE(r.anisotropy.ratio_lower95, 0.0);
        QVERIFY(std::isinf(r.anisotropy.ratio_upper95));
    }

    void aTiedFitIsNotAssessed()
    {
        FitResult r;
        r.variables = fit_variables(ModelVariant::Baseline, true);
        r.best_coords = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(r.variables.size()));
        assess_anisotropy(r);
        QVERIFY(!r.anisotropy.assessed);
    }

    void aRatioBeyondTheTypicalNeedsTwoSetups()
    {
        const FitOptions o = drape_fit_defaults();
        QCOMPARE(o.typical_bending_anisotropy, 3.0);
        // 10:1, separated: one set-up confirming it is not enough; two are.
        FitResult r = free_fit(-4.0, -5.0, 1e-3);
        assess_anisotropy(r);
        QVERIFY(r.anisotropy.separated);
        r.anisotropy.setups = 1;
        r.anisotropy.setups_confirming = 1;
        QVERIFY(!anisotropy_stands(r, o));
        r.anisotropy.setups = 2;
        r.anisotropy.setups_confirming = 2;
        QVERIFY(anisotropy_stands(r, o));
        QVERIFY2(r.anisotropy.reason.find("2 of the records' 2") != std::string::npos, r.anisotropy.reason.c_str());
        // Within the typical factor the fitted ratio stands, separated or not.
        FitResult typical = free_fit(-4.7, -5.0, 1.0);
        assess_anisotropy(typical);
        QVERIFY(!typical.anisotropy.separated);
        QVERIFY(anisotropy_stands(typical, o));
        QVERIFY(typical.anisotropy.reason.find("kept as fitted") != std::string::npos);
        // Beyond it and not separated: the tie decides, even with two set-ups.
        FitResult unseparated = free_fit(-4.0, -5.0, 1.0);
        assess_anisotropy(unseparated);
        unseparated.anisotropy.setups_confirming = 2;
        QVERIFY(!anisotropy_stands(unseparated, o));
    }

    void theHeldShearSaysSo()
    {
        FitResult r;
        ParamEstimate e;
        e.id = Param::Shear;
        e.role = "fitted";
        r.estimates.push_back(e);
        mark_held_shear(r); // not held: nothing changes
        QCOMPARE(r.estimates.front().role, std::string("fitted"));
        r.shear_hold.held = true;
        r.shear_hold.held_N_m = 56.2;
        r.shear_hold.lower95_N_m = 1.0;
        r.shear_hold.upper95_N_m = 900.0;
        r.shear_hold.at_bound = true;
        mark_held_shear(r);
        const ParamEstimate& h = r.estimates.front();
        QCOMPARE(h.role, std::string("held"));
        QVERIFY(!h.constrained);
        QVERIFY2(h.note.find("56.2 N/m") != std::string::npos && h.note.find("at a fit bound") != std::string::npos, h.note.c_str());
    }

    void runsAddTheirWorkAndJoinTheirTraces()
    {
        FitResult first, second;
        first.evaluations = 10;
        first.simulations = 40;
        first.simulation_seconds = 40.0;
        first.wall_seconds = 50;
        first.factorisations = 7;
        first.trace = {{1, "scan", 5, 5, {}, 2.0}, {10, "local", 3, 3, {}, 50.0}};
        second.evaluations = 4;
        second.simulations = 10;
        second.simulation_seconds = 20.0;
        second.wall_seconds = 30;
        second.factorisations = 3;
        second.trace = {{1, "local", 4, 4, {}, 5.0}, {4, "mirror", 2, 2, {}, 30.0}};
        second.cancelled = true;
        const FitResult kept = combine_runs(first, second, true, "tie ");
        QCOMPARE(kept.evaluations, 14);
        QCOMPARE(kept.simulations, 50L);
        QCOMPARE(kept.factorisations, 10L);
        QCOMPARE(kept.wall_seconds, 80.0);
        // Seconds per simulation weighted by the simulations: (40 * 1 + 10 * 2) / 50.
        QVERIFY(std::abs(kept.seconds_per_simulation() - 1.2) < 1e-12);
        // What one stage did is the difference of two snapshots.
        const WorkCounters stage = static_cast<const WorkCounters&>(kept) - first;
        QCOMPARE(stage.evaluations, 4);
        QCOMPARE(stage.simulations, 10L);
        QCOMPARE(stage.factorisations, 3L);
        QCOMPARE(stage.seconds_per_simulation(), 2.0);
        QCOMPARE(int(kept.trace.size()), 4);
        QCOMPARE(kept.trace[2].evaluation, 11);
        QCOMPARE(kept.trace[2].stage, std::string("tie local"));
        QCOMPARE(kept.trace[3].elapsed_s, 80.0);
        QVERIFY(kept.cancelled); // the run was stopped, whichever result is kept
        // Keeping the first: its own numbers, the second's work added.
        const FitResult first_kept = combine_runs(first, second, false, "tie ");
        QCOMPARE(first_kept.evaluations, 14);
        QCOMPARE(first_kept.trace.front().stage, std::string("scan"));
    }

    void theReportNeverContradictsTheNamedEffect()
    {
        // The candidate library named an effect while the matched filters (an older,
        // narrower screen) flagged nothing: report.md says what the JSON says.
        FitResult r = free_fit(-5.0, -5.0, 0.01);
        const EffectCandidate c{.name = "profiler_scale",
                                .family = "instrument",
                                .description = "the profiler reads radii scaled",
                                .z = 5.1,
                                .delta_chi2 = 26.0,
                                .information = 20.0,
                                .amplitude = 1.5,
                                .amplitudes = {1.5},
                                .amplitude_unit = "%",
                                .verdict = "beyond noise",
                                .note = "",
                                .channels = {},
                                .explains_reached = true};
        r.residual.candidates = {c};
        r.residual.named_effect = c.name;
        r.residual.exceeds_noise = true;
        const QString md = report_md(r);
        QVERIFY(!md.isEmpty());
        QVERIFY2(md.contains("Named effect: **profiler_scale**"), qPrintable(md));
        QVERIFY2(!md.contains("No candidate effect"), qPrintable(md));
        // Without the library's refits, the matched filters' word stands.
        FitResult plain = free_fit(-5.0, -5.0, 0.01);
        QVERIFY(report_md(plain).contains("No candidate effect"));
    }

    void aRecordBelowThePresetsFreeStripsIsOutOfReach()
    {
        // DL-D1's fabric (125 g/m^2) at 240/180 mm reads 55.4 %: free strips of
        // B 4e-6 N*m reach 68.5 %, so no drape of that bending gets down to it; the
        // largest bending that can is about 2.7e-6 (tst_physics checks the strips and
        // that drapes lie above them).
        auto fit_at = [](double bending) {
            FitResult r = free_fit(std::log10(bending), std::log10(bending), 0.01);
            r.params[Param::BendWarp] = r.params[Param::BendWeft] = bending;
            RecordFit rf;
            rf.measured.id = "short-overhang";
            rf.measured.sample_diameter = 0.24;
            rf.measured.disc_diameter = 0.18;
            rf.measured.areal_density = 0.125;
            rf.measured_features.drape_coefficient_percent = 55.4;
            r.records.push_back(rf);
            check_free_strips(r);
            return r;
        };
        FitResult stiff = fit_at(4e-6);
        const RecordFit& s = stiff.records[0];
        QVERIFY2(std::abs(s.free_strip_preset_dc_percent - 68.5) < 0.3, qPrintable(QString::number(s.free_strip_preset_dc_percent)));
        QVERIFY(s.free_strip_bound_Nm > 2.4e-6 && s.free_strip_bound_Nm < 2.8e-6);
        QVERIFY(s.below_free_strips);
        QCOMPARE(fit_to_json(stiff)["fit"]["records"][0]["below_free_strips"].get<bool>(), true);
        const QString md = report_md(stiff);
        QVERIFY2(md.contains("Out of any drape's reach") && md.contains("| short-overhang | 240/180 | 55.4 | 68.5 |"), qPrintable(md));
        // A bending below the bound: within reach, and the report says nothing.
        FitResult limp = fit_at(2e-6);
        QVERIFY(!limp.records[0].below_free_strips);
        QVERIFY(limp.records[0].free_strip_preset_dc_percent < 55.4);
        const QString limp_md = report_md(limp);
        QVERIFY(!limp_md.isEmpty());
        QVERIFY(!limp_md.contains("Out of any drape's reach"));
        // No declared weight: no bound.
        FitResult unknown = fit_at(4e-6);
        unknown.records[0].measured.areal_density = 0;
        check_free_strips(unknown);
        QVERIFY(std::isnan(unknown.records[0].free_strip_bound_Nm) && !unknown.records[0].below_free_strips);
    }

    void stageNames()
    {
        QCOMPARE(std::string(to_string(Stage::FromFlatFoldCount)), std::string("from flat, fold count"));
        QCOMPARE(std::string(to_string(Stage::Done)), std::string("done"));
        FitProgress p;
        p.stage = "tie from flat";
        p.stage_id = Stage::FromFlat;
        p.search = false;
        p.starting = true;
        const std::string line = fit_progress_line(p);
        QVERIFY2(line.find("tie from flat:") == 0 && line.find("the preset from flat") != std::string::npos, line.c_str());
    }
};

QTEST_APPLESS_MAIN(TestPolicies)
#include "tst_policies.moc"
