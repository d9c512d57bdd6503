// Undeclared effects (issue 7): records made by the engine with an effect the
// fitting model has switched off - the cloth wrapping the pedestal rim (edge
// contact, the effect traced on set-a in docs/model-discrepancy.md) and a
// profiler off the pedestal axis (measurement) - are fitted without declaring it. The residual report must flag
// a discrepancy beyond noise and name the right signature; fitting with the
// effect enabled must bring the residual down to the noise; a clean record must
// not be flagged.
#include "engine/estimate/fit.hpp"
#include "synthetic.hpp"

#include <QTest>

#include <algorithm>
#include <cmath>

using namespace drape;
using namespace drape::estimate;
using cloth::Param;

namespace {
cloth::FabricParams truth()
{
    cloth::FabricParams p;
    p[Param::BendWarp] = 1.5e-5;
    p[Param::BendWeft] = 1.0e-5;
    p[Param::Shear] = 20;
    p[Param::AreaDensity] = 0.2;
    return p;
}

constexpr int kGrid = 17;

MeasuredDrape synthetic(const cloth::FabricParams& p, std::uint64_t seed)
{
    return test::synthetic_record(p, test::drape_setup(0.30, 0.15, kGrid, seed));
}

FitOptions options(ModelVariant m)
{
    FitOptions o;
    o.model = m;
    o.grid = kGrid;
    o.seed = 1;
    o.seeds_per_evaluation = 1;
    o.scan_evaluations = 6;
    o.global_evaluations = 8;
    o.local_evaluations = 30;
    o.spread_seeds = 3;
    return o;
}

bool has(const std::vector<std::string>& v, const std::string& s) { return std::find(v.begin(), v.end(), s) != v.end(); }

void describe(const char* what, const FitResult& r)
{
    std::string effects;
    for (const auto& e : r.residual.candidate_effects) effects += e + " ";
    qInfo("%s: chi2 %.1f / dof %d, exceeds %d, D error %+.2f, candidates [%s]", what, r.chi2, r.dof, int(r.residual.exceeds_noise),
          r.records[0].dc_error_percent, effects.c_str());
    std::string kinds, radius, folds, h1;
    for (const auto& [k, v] : r.residual.kind_rms) kinds += k + " " + QString::number(v, 'f', 2).toStdString() + "  ";
    for (const auto& t : r.residuals) {
        if (t.kind == "mean_radius") radius += QString::number(t.whitened(), 'f', 1).toStdString() + " ";
        if (t.kind == "fold_rms") folds += QString::number(t.whitened(), 'f', 1).toStdString() + " ";
        if (t.kind == "cos1" || t.kind == "sin1")
            h1 += QString("%1 %2/%3 mm (sigma %4) ").arg(QString::fromStdString(t.kind)).arg(t.simulated * 1e3, 0, 'f', 1).arg(t.measured * 1e3, 0, 'f', 1).arg(t.sigma * 1e3, 0, 'f', 1).toStdString();
    }
    std::string because;
    for (const auto& b : r.residual.exceeds_because) because += b + "; ";
    if (!because.empty()) qInfo("  beyond noise because: %s", because.c_str());
    qInfo("  whitened rms per kind: %s", kinds.c_str());
    for (const auto& [k, z] : r.residual.signature_z) qInfo("  signature %s: z = %.2f", k.c_str(), z);
    qInfo("  mean radius by depth (whitened): %s", radius.c_str());
    qInfo("  fold rms by depth (whitened): %s", folds.c_str());
    qInfo("  signed a1, b1 by depth, simulated/measured: %s", h1.c_str());
    qInfo("  nodes measured %.1f, fitted %.1f (branch %d)", r.records[0].measured_features.node_count,
          r.records[0].simulated_features.node_count, r.records[0].branch_folds);
}
} // namespace

class TestDiscrepancy : public QObject {
    Q_OBJECT
private slots:
    void cleanRecordIsNotFlagged()
    {
        const FitResult r = fit_fabric({synthetic(truth(), 5)}, options(ModelVariant::Baseline));
        describe("clean, baseline", r);
        QVERIFY(!r.residual.exceeds_noise);
        QVERIFY(r.residual.candidate_effects.empty());
    }

    void hiddenRimWrappingIsFlaggedAndExplained()
    {
        // The truth wraps the pedestal rim (edge contact); the fitting model has
        // vertex contact only, so its coarse elements cut the rim - the residual
        // traced on set-a (docs/model-discrepancy.md).
        // Two seeds per evaluation (the CLI's default): with one, the drape-to-drape
        // floors leave this signature at about 3 sigma on a single grid-17 drape.
        // Two repeat specimens (records 5 and 6, as a lab tests repeats): on one
        // record the signature's z was 2.4-7.8 over record seeds 1-8 (5 of 8 above
        // 3; 2.47 on record 5 with this machine's BLAS, which had passed on
        // another), a single realisation at the edge of detection. On two it is
        // 13.9 (5.2 with OpenBLAS's Haswell kernels), the pair 1 and 4 (the two
        // weakest alone) 6.8, and the edge-contact control stays below 3 (1.0, 2.1).
        const std::vector<MeasuredDrape> rec = {synthetic(truth(), 5), synthetic(truth(), 6)};
        FitOptions o = options(ModelVariant::Baseline);
        o.seeds_per_evaluation = 2;
        o.model_options.edge_contact = false;
        const FitResult base = fit_fabric(rec, o);
        describe("rim wrapping hidden, vertex contact only", base);
        QVERIFY(base.residual.exceeds_noise);
        QVERIFY(has(base.residual.candidate_effects, "rim_wrapping"));
        o.model_options.edge_contact = true;
        const FitResult with = fit_fabric(rec, o);
        describe("rim wrapping hidden, edge contact", with);
        QVERIFY(!with.residual.exceeds_noise);
        QVERIFY(with.residual.candidate_effects.empty());
        QVERIFY(with.chi2 < base.chi2);
    }

    void hiddenProfilerDepthDatumIsNamed()
    {
        // The profiler's cuts taken 6 mm deeper than the record declares (its height
        // datum off): every slice wider than the model's at the declared depth while
        // the photos' D and hem are right - the contour half of the rim signature
        // the set-a fits show (docs/model-discrepancy.md, "What the residual still shows"): the fit stiffens
        // the bending to widen the slices and D pays (+3.1 points as fitted). The
        // candidate profiler_depth is beyond noise with its amplitude near the 6 mm
        // (4.7 mm: the rest went into the bending); on the clean record
        // (cleanRecordIsNotFlagged) it is not. (3 mm at this grid and noise: absorbed,
        // chi2 12 / 71, nothing beyond noise.)
        constexpr double kDeeper = 0.006;
        cloth::DrapeSetup s = test::drape_setup(0.30, 0.15, kGrid, 5);
        for (double& d : s.slice_depths) d += kDeeper;
        MeasuredDrape rec = synthesize_record(cloth::simulate_drape(truth(), s), s, truth(), 0.3e-3, s.seed + 100, "deeper cuts");
        for (auto& c : rec.contours) c.depth_m -= kDeeper; // declared at the usual depths
        const FitResult r = fit_fabric({rec}, options(ModelVariant::Baseline));
        describe("profiler depth datum 6 mm off, baseline", r);
        const EffectCandidate* depth = nullptr;
        for (const auto& c : r.residual.candidates) {
            qInfo("  candidate %s: %s, delta chi2 %.1f, amplitude %.3g %s", c.name.c_str(), c.verdict.c_str(), c.delta_chi2, c.amplitude,
                  c.amplitude_unit.c_str());
            if (c.name == "profiler_depth") depth = &c;
        }
        QVERIFY(depth);
        QCOMPARE(depth->verdict, std::string("beyond noise"));
        QVERIFY2(depth->amplitude > 0.5 * kDeeper && depth->amplitude < 1.5 * kDeeper, qPrintable(QString::number(depth->amplitude)));
        // Named: the one beyond noise (profiler_scale, its look-alike on DL-A10, reads
        // 2.8 here against 11.3), and it explains the residual (name_effect).
        QCOMPARE(r.residual.named_effect, std::string("profiler_depth"));
    }

    void hiddenProfilerOffsetIsFlaggedAndExplained()
    {
        MeasuredDrape rec = synthetic(truth(), 5);
        for (auto& c : rec.contours) { // the profiler's axis 8 mm off the pedestal's, along +x
            cloth::Polygon2 poly = cloth::polygon_from_profile(c.profile);
            for (auto& v : poly) v.x() += 0.008;
            c.profile = cloth::radial_profile(poly, c.profile.size());
        }
        const FitResult base = fit_fabric({rec}, options(ModelVariant::Baseline));
        describe("off-centre profiler hidden, baseline", base);
        QVERIFY(base.residual.exceeds_noise);
        QVERIFY(has(base.residual.candidate_effects, "specimen_off_centre"));
        FitOptions o = options(ModelVariant::Baseline);
        o.recentre_contours = true;
        const FitResult with = fit_fabric({rec}, o);
        describe("off-centre profiler hidden, re-centred contours", with);
        qInfo("estimated profiler axis offset: %.2f, %.2f mm", with.records[0].measured_features.axis_offset_m.x() * 1e3,
              with.records[0].measured_features.axis_offset_m.y() * 1e3);
        QVERIFY(!with.residual.exceeds_noise);
        QVERIFY(std::abs(with.records[0].measured_features.axis_offset_m.x() - 0.008) < 0.002);
    }
};

int main(int argc, char** argv)
{
    if (qEnvironmentVariableIsEmpty("QTEST_FUNCTION_TIMEOUT")) qputenv("QTEST_FUNCTION_TIMEOUT", "1800000");
    TestDiscrepancy t;
    return QTest::qExec(&t, argc, argv);
}
#include "tst_discrepancy.moc"
