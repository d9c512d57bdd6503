// Long fit checks (label slow): interval coverage over several perturbation
// seeds, a joint fit of two set-ups, prediction of other set-ups from a fit at
// 300/150 against known truth, non-identifiable parameters of the full model,
// and a record with an undeclared measurement effect (off-centre profiler).
#include "engine/core/error.hpp"
#include "engine/estimate/fit.hpp"
#include "synthetic.hpp"

#include <QTest>

#include <cmath>
#include <numbers>
#include <vector>

using namespace drape;
using namespace drape::estimate;
using cloth::Param;

namespace {
constexpr int kGrid = 41;

cloth::FabricParams truth()
{
    cloth::FabricParams p;
    p[Param::BendWarp] = 1.5e-5;
    p[Param::BendWeft] = 6.0e-6;
    p[Param::Shear] = 20;
    p[Param::AreaDensity] = 0.18;
    return p;
}

cloth::DrapeSetup setup(double D1, double D2, std::uint64_t seed)
{
    return test::drape_setup(D1, D2, static_cast<int>(std::lround(kGrid * D1 / 0.30)) | 1, seed);
}

MeasuredDrape synthetic(const cloth::FabricParams& p, double D1, double D2, std::uint64_t seed)
{
    return test::synthetic_record(p, setup(D1, D2, seed), "synthetic-" + std::to_string(seed));
}

const ParamEstimate& est(const FitResult& r, Param p)
{
    for (const auto& e : r.estimates)
        if (e.id == p) return e;
    throw std::logic_error("missing estimate");
}

FitOptions options()
{
    FitOptions o;
    o.grid = kGrid;
    o.seed = 1;
    return o;
}

double mean_dc(const cloth::FabricParams& p, double D1, double D2)
{
    double d = 0;
    for (std::uint64_t s = 1; s <= 3; ++s) d += cloth::simulate_drape(p, setup(D1, D2, s)).metrics.drape_coefficient_percent / 3;
    return d;
}
} // namespace

class TestFitSlow : public QObject {
    Q_OBJECT
private slots:
    void coverageAndPrediction()
    {
        // Issue 15: a known fabric, measured as the lab would from five drapes
        // (perturbation seeds 11-15, each from flat), fitted at 300/150 mm; on at
        // least 4 of the 5 every fitted parameter's 95 % interval holds the truth
        // (a shear held at the typical value is not an estimate: its interval is
        // what the data left open, so it is not counted; tied bendings are one
        // coordinate with two truths and count as two intervals; an interval wider
        // than a decade counts as reported, and the number of those is printed).
        const auto p = truth();
        int seeds_inside = 0, intervals = 0, inside = 0, loose = 0, good_fits = 0;
        const std::vector<std::uint64_t> seeds{11, 12, 13, 14, 15};
        FitResult first;
        for (std::uint64_t seed : seeds) {
            const FitResult r = fit_fabric({synthetic(p, 0.30, 0.15, seed)}, options());
            bool all = true;
            for (const auto& e : r.estimates) {
                if (e.role != "fitted") continue;
                const bool in = e.lower95 <= p[e.id] && p[e.id] <= e.upper95;
                qInfo("seed %d %s truth %.3g fitted %.3g [%.3g, %.3g]%s", int(seed), e.key.c_str(), p[e.id], e.value, e.lower95, e.upper95,
                      in ? "" : " - misses");
                ++intervals;
                inside += in ? 1 : 0;
                loose += e.constrained ? 0 : 1;
                all = all && in;
            }
            seeds_inside += all ? 1 : 0;
            qInfo("  D error %+.2f, node error %+.2f, %ld simulations, %.2f s each; %s%s", r.records[0].dc_error_percent, r.records[0].node_error,
                  r.simulations, r.seconds_per_simulation(), r.anisotropy.reason.c_str(), r.grid_bound ? "; grid-bound" : "");
            if (r.shear_hold.assessed) qInfo("  %s", r.shear_hold.reason.c_str());
            good_fits += (std::abs(r.records[0].dc_error_percent) < 2.0 && std::abs(r.records[0].node_error) <= 1.0) ? 1 : 0;
            if (seed == 11) first = r;
        }
        qInfo("every interval holds the truth on %d of %d seeds (%d of %d intervals, %d of them not constrained)", seeds_inside,
              int(seeds.size()), inside, intervals, loose);
        QVERIFY(intervals >= 2 * static_cast<int>(seeds.size())); // both bendings of every fit (none held)

        // Prediction of set-ups the fit never saw, against the known truth
        // (D averaged over 3 perturbation seeds on both sides).
        for (auto [D1, D2] : {std::pair{0.24, 0.18}, std::pair{0.36, 0.18}}) {
            cloth::FabricParams fp = first.params;
            const double dt = mean_dc(p, D1, D2), df = mean_dc(fp, D1, D2);
            qInfo("predict %.0f/%.0f mm: truth D %.1f, predicted %.1f", D1 * 1e3, D2 * 1e3, dt, df);
            QVERIFY(std::abs(dt - df) < 3.0);
        }
        // issue 4: D within 2 points and nodes within 1 for every fit
        QCOMPARE(good_fits, static_cast<int>(seeds.size()));
        QVERIFY2(seeds_inside >= 4, qPrintable(QString("every interval holds the truth on %1 of 5 seeds").arg(seeds_inside)));
    }

    void jointFitOfTwoSetups()
    {
        const auto p = truth();
        const FitResult r = fit_fabric({synthetic(p, 0.30, 0.15, 21), synthetic(p, 0.36, 0.18, 22)}, options());
        QCOMPARE(r.records.size(), std::size_t(2));
        for (Param q : {Param::BendWarp, Param::BendWeft}) {
            const auto& e = est(r, q);
            qInfo("joint %s truth %.3g fitted %.3g [%.3g, %.3g]", e.key.c_str(), p[q], e.value, e.lower95, e.upper95);
            QVERIFY(e.lower95 <= p[q] && p[q] <= e.upper95);
        }
        for (const auto& rf : r.records) {
            qInfo("joint %.0f/%.0f mm: D error %+.2f, node error %+.2f (chi2 %.1f / %d, %d evaluations)", rf.setup.sample_diameter * 1e3,
                  rf.setup.disc_diameter * 1e3, rf.dc_error_percent, rf.node_error, r.chi2, r.dof, r.evaluations);
            QVERIFY(std::abs(rf.dc_error_percent) < 2.5);
        }
    }

    void fullModelReportsUnconstrainedParameters()
    {
        FitOptions o = options();
        o.model = ModelVariant::Full;
        const FitResult r = fit_fabric({synthetic(truth(), 0.30, 0.15, 31)}, o);
        // At 2000 N/m a 300 mm specimen hardly stretches under its own weight,
        // so the drape cannot tell the tensile stiffnesses.
        int unconstrained = 0;
        for (Param q : {Param::StretchWarp, Param::StretchWeft}) {
            qInfo("%s: %s", est(r, q).key.c_str(), est(r, q).note.c_str());
            unconstrained += est(r, q).constrained ? 0 : 1;
        }
        QVERIFY(unconstrained >= 1);
    }

    void undeclaredOffCentreProfiler()
    {
        // The profiler's axis 6 mm off the pedestal axis (a measurement effect
        // the fit does not model): every contour is shifted.
        MeasuredDrape rec = synthetic(truth(), 0.30, 0.15, 41);
        for (auto& c : rec.contours) {
            cloth::Polygon2 poly = cloth::polygon_from_profile(c.profile);
            for (auto& v : poly) v.x() += 0.006;
            c.profile = cloth::radial_profile(poly, 360);
        }
        const FitResult bad = fit_fabric({rec}, options());
        qInfo("off-centre: exceeds %d, dominant harmonic %d", int(bad.residual.exceeds_noise),
              bad.residual.dominant_harmonics.empty() ? -1 : bad.residual.dominant_harmonics.front());
        QVERIFY(bad.residual.exceeds_noise);
        QVERIFY(std::find(bad.residual.candidate_effects.begin(), bad.residual.candidate_effects.end(), "specimen_off_centre") !=
                bad.residual.candidate_effects.end());
        const FitResult clean = fit_fabric({synthetic(truth(), 0.30, 0.15, 41)}, options());
        QVERIFY(std::find(clean.residual.candidate_effects.begin(), clean.residual.candidate_effects.end(), "specimen_off_centre") ==
                clean.residual.candidate_effects.end());
    }
};

// Each function runs several full fits (minutes each on a loaded 2-core
// machine): lift Qt Test's 5-minute per-function watchdog.
int main(int argc, char** argv)
{
    if (qEnvironmentVariableIsEmpty("QTEST_FUNCTION_TIMEOUT")) qputenv("QTEST_FUNCTION_TIMEOUT", "3000000");
    TestFitSlow t;
    return QTest::qExec(&t, argc, argv);
}
#include "tst_fit_slow.moc"
