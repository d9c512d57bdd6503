// The blind suite of undeclared effects (issue 20), small version: synthetic
// records made by the engine with one effect switched on that the record does
// not declare (or none), measured like the lab (0.3 mm laser noise), fitted with
// the baseline model; the residual report must name the injected effect and
// raise no alarm on a clean record. The full suite (more strengths, phases,
// seeds and clean records) is tst_est_blind_slow (`slow`).
#include "engine/estimate/fit.hpp"
#include "blind.hpp"

#include <QTest>

#include <cmath>
#include <cstdio>
#include <random>
#include <set>
#include <string>

using namespace drape;
using namespace drape::estimate;
using cloth::Param;

using namespace drape::estimate::test::blind;

namespace {

void describe(const FitResult& r)
{
    qInfo("chi2 %.1f / %d, exceeds noise %d, named '%s' %s", r.chi2, r.dof, int(r.residual.exceeds_noise), r.residual.named_effect.c_str(),
          r.residual.unexplained.c_str());
    for (const auto& c : r.residual.candidates)
        if (c.verdict != "not testable")
            qInfo("  %-20s %-12s z %+6.2f  dchi2 %6.2f  info %+6.2f  amp %+.3g %s%s%s", c.name.c_str(), c.verdict.c_str(), c.z, c.delta_chi2,
                  c.information, c.amplitude, c.amplitude_unit.c_str(), std::isfinite(c.verified_delta_chi2) ? (" verified " + std::to_string(c.verified_delta_chi2)).c_str() : "",
                  c.note.empty() ? "" : (" - " + c.note).c_str());
}

} // namespace

class TestBlind : public QObject {
    Q_OBJECT
private slots:
    void statisticsOfAKnownSignature()
    {
        // The tests against an analytic case: residual = noise + a * s with s
        // partly inside the fitted columns. The refit's delta chi2 is the squared
        // projection of r on the new part of s; the amplitude comes back.
        std::mt19937_64 rng(5);
        std::normal_distribution<double> g(0.0, 1.0);
        const int N = 400;
        Eigen::MatrixXd J(N, 2);
        Eigen::VectorXd s(N), noise(N);
        for (int i = 0; i < N; ++i) {
            J(i, 0) = std::sin(0.05 * i);
            J(i, 1) = std::cos(0.031 * i);
            s[i] = 0.5 * J(i, 0) + std::sin(0.2 * i) * 0.8; // half of it the fitted column's
            noise[i] = g(rng);
        }
        EffectSpec spec;
        spec.name = "test_effect";
        spec.family = "test";
        EffectSignature sig;
        sig.spec = &spec;
        sig.columns = s;
        for (double a : {0.0, 0.5}) {
            const Eigen::VectorXd r = noise + a * s;
            const auto c = test_candidates(J, r, {sig}, N);
            QCOMPARE(c.size(), std::size_t(1));
            qInfo("a %.1f: z %.2f, delta chi2 %.2f, amplitude %.3f, %s", a, c[0].z, c[0].delta_chi2, c[0].amplitude, c[0].verdict.c_str());
            QVERIFY(std::abs(c[0].z * c[0].z - c[0].delta_chi2) < 1e-9 * std::max(1.0, c[0].delta_chi2));
            if (a == 0) {
                QCOMPARE(c[0].verdict, std::string("within noise"));
                QVERIFY(std::abs(c[0].z) < 3);
            } else {
                QCOMPARE(c[0].verdict, std::string("beyond noise"));
                QVERIFY(std::abs(c[0].amplitude + a) < 0.15); // the refit removes -a s
                QCOMPARE(name_effect(c, r.squaredNorm(), N - 2), std::string("test_effect"));
            }
        }
        // A fit worse than its noise model by a factor 4 in chi2: z halves, delta
        // chi2 quarters, the refit's amplitude is the same.
        {
            const Eigen::VectorXd r = noise + 0.5 * s;
            const auto one = test_candidates(J, r, {sig}, N)[0], four = test_candidates(J, r, {sig}, N, 4.0)[0];
            QVERIFY(std::abs(four.z - one.z / 2) < 1e-12 * std::abs(one.z));
            QVERIFY(std::abs(four.delta_chi2 - one.delta_chi2 / 4) < 1e-12 * one.delta_chi2);
            QCOMPARE(four.amplitude, one.amplitude);
            QCOMPARE(four.amplitudes.size(), std::size_t(1));
        }
        // A signature the fitted columns already make is not testable.
        sig.columns = 2 * J.col(0);
        QCOMPARE(test_candidates(J, noise, {sig}, N)[0].verdict, std::string("not testable"));
    }

    /// The naming rule's channels: a refit that explains the contours by making
    /// the photos worse is reported, not named. Analytic: rows 0-1 photos, 2-3 contours, no
    /// fitted columns, the signature (2, 2, -1, -1) against the residual (0, 0, 3, 3)
    /// refits with amplitude 0.6: photos 0 -> 2.88, contours 18 -> 11.52.
    void aRefitThatTradesChannelsIsNotNamed()
    {
        EffectSpec spec;
        spec.name = "trading";
        spec.family = "test";
        EffectSignature sig;
        sig.spec = &spec;
        sig.columns = Eigen::Vector4d(2, 2, -1, -1);
        const Eigen::Vector4d r(0, 0, 3, 3);
        const Eigen::MatrixXd J(4, 0);
        auto unchecked = test_candidates(J, r, {sig}, 4);
        unchecked[0].verdict = "beyond noise"; // (four rows cannot reach the 3-sigma quantile; the rule under test comes after it)
        QVERIFY(unchecked[0].channels.empty());
        QCOMPARE(name_effect(unchecked, 10.0, 4), std::string("trading")); // (a chi2 the refit brings within the noise)
        const std::vector<int> channel{0, 0, 1, 1};
        auto c = test_candidates(J, r, {sig}, 4, 1.0, channel);
        c[0].verdict = "beyond noise";
        QCOMPARE(c[0].channels.size(), std::size_t(2));
        QCOMPARE(c[0].channels[0].name, std::string("photos"));
        QVERIFY(std::abs(c[0].channels[0].reach - 0.8) < 1e-12 && std::abs(c[0].channels[0].delta_chi2 + 2.88) < 1e-9);
        QVERIFY(std::abs(c[0].channels[1].reach - 0.2) < 1e-12 && std::abs(c[0].channels[1].delta_chi2 - 6.48) < 1e-9);
        QVERIFY(!c[0].explains_reached);
        QVERIFY(name_effect(c, 10.0, 4).empty());
        // Explaining both channels: named again.
        auto both = test_candidates(J, Eigen::Vector4d(2, 2, -1, -1), {sig}, 4, 1.0, channel);
        both[0].verdict = "beyond noise";
        QVERIFY(both[0].explains_reached);
        QCOMPARE(name_effect(both, 10.0, 4), std::string("trading"));
    }

    void libraryAndWhatTheFitCovers()
    {
        // The candidates issue 20 lists, each once in the library.
        std::set<std::string> names;
        for (const auto& e : effect_library()) QVERIFY2(names.insert(e.name).second, e.name.c_str());
        for (const char* n : {"profiler_off_axis", "profiler_tilt", "camera_scale", "profiler_scale", "profiler_depth", "specimen_weight_gradient", "buckling",
                              "tensile_stiffness", "tensile_anisotropy", "shear_stiffness", "bending_stiffening", "bending_softening",
                              "bending_anisotropy", "declared_weight", "declared_thickness", "disc_grip", "self_contact", "contact_resolution"})
            QVERIFY2(names.count(n), n);
        auto spec = [](const std::string& n) {
            for (const auto& e : effect_library())
                if (e.name == n) return e;
            return EffectSpec{};
        };
        // Warp and weft fitted apart cover their ratio; tied, the ratio is free.
        const FitOptions o;
        QVERIFY(!fitted_by(spec("bending_anisotropy"), fit_variables(o.model, false)).empty());
        QVERIFY(fitted_by(spec("bending_anisotropy"), fit_variables(o.model, true)).empty());
        // The held tensile stiffness is not covered, either way round; shear is fitted.
        QVERIFY(fitted_by(spec("tensile_anisotropy"), fit_variables(o.model, false)).empty());
        QVERIFY(fitted_by(spec("tensile_stiffness"), fit_variables(o.model, false)).empty());
        QCOMPARE(fitted_by(spec("shear_stiffness"), fit_variables(o.model, false)), std::string("shear_N_m"));
        // One of a pair fitted alone does not cover the pair's common change.
        FitVariable warp;
        warp.params = {Param::StretchWarp};
        QVERIFY(fitted_by(spec("tensile_stiffness"), {warp}).empty());
        QVERIFY(fitted_by(spec("self_contact"), {warp}).empty()); // a switch: no parameters
        // A variable that ties two parameters does not cover an effect on one of them.
        FitVariable tied;
        tied.params = {Param::BendWarp, Param::BendWeft};
        EffectSpec warp_only;
        warp_only.params = {Param::BendWarp};
        QVERIFY(fitted_by(warp_only, {tied}).empty());
        FitVariable weft;
        weft.params = {Param::BendWeft};
        QVERIFY(!fitted_by(warp_only, {tied, weft}).empty()); // with weft on its own, warp is free too
    }

    void injectedEffectIsNamed_data()
    {
        QTest::addColumn<QString>("effect");
        QTest::addColumn<double>("strength");
        QTest::newRow("profiler 8 mm off axis") << "profiler_off_axis" << 8e-3;
        // At the stated detection limit (docs/model-discrepancy.md, "Detection limits
        // now": 12 %, z 7.1 and 7.9 on the slow suite's records). At 5 % D's noise
        // (about 1.4 points after the drape-to-drape floor, against 0.8 point of D
        // per % of scale) leaves z near 3 and the name to the realisation: 1 of 2
        // records there, and record 11 went from named to z 2.3 with another BLAS.
        QTest::newRow("camera scale +12 %") << "camera_scale" << 0.12;
        QTest::newRow("vertex contact") << "contact_resolution" << 1.0;
    }
    void injectedEffectIsNamed()
    {
        QFETCH(QString, effect);
        QFETCH(double, strength);
        const FitResult r = fit(injected(effect.toStdString(), strength, 11));
        describe(r);
        QCOMPARE(QString::fromStdString(r.residual.named_effect), effect);
    }

    void absorbedEffectIsNotMisnamed()
    {
        // A gripping disc leaves no residual the baseline refit cannot absorb
        // (bending and shear make up for it on one 300/150 drape): the report must
        // not name another effect for it (docs/model-discrepancy.md, detection limits).
        const FitResult r = fit(injected("disc_grip", 1.0, 11));
        describe(r);
        QVERIFY(r.residual.named_effect.empty() || r.residual.named_effect == "disc_grip");
    }

    void cleanRecordRaisesNoAlarm()
    {
        const FitResult r = fit(injected("none", 0, 11));
        describe(r);
        QVERIFY(r.residual.named_effect.empty());
        for (const auto& c : r.residual.candidates) QVERIFY2(c.verdict != "beyond noise", c.name.c_str());
        // The new candidates are tested; a drapemeter's folds do not touch.
        for (const auto& c : r.residual.candidates) {
            if (c.name == "profiler_tilt" || c.name == "specimen_weight_gradient") {
                QCOMPARE(c.verdict, std::string("within noise"));
                QCOMPARE(c.amplitudes.size(), std::size_t(2));
            }
            if (c.name == "self_contact") {
                QCOMPARE(c.verdict, std::string("not testable"));
                QVERIFY2(c.note.find("changes none") != std::string::npos, c.note.c_str());
            }
        }
        // The JSON contract of `drape fit --json`.
        const auto j = fit_to_json(r);
        QVERIFY(j["residual"].contains("exceeds_noise"));
        QVERIFY(j["residual"]["candidates"].is_array() && !j["residual"]["candidates"].empty());
        QVERIFY(j["residual"]["named_effect"].is_null());
        for (const auto& c : j["residual"]["candidates"]) {
            QVERIFY(c.contains("name") && c.contains("verdict"));
            if (c["verdict"] != "not testable") QVERIFY(c.contains("z") && c.contains("delta_chi2"));
        }
    }
};

QTEST_APPLESS_MAIN(TestBlind)
#include "tst_blind.moc"
