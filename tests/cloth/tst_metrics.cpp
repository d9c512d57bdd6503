// The shared metric path on contours with known answers.
#include "engine/core/error.hpp"
#include "engine/cloth/metrics.hpp"

#include <QTest>

#include <Eigen/QR>

#include <numbers>
#include <random>

using namespace drape::cloth;

namespace {
constexpr double kPi = std::numbers::pi;

Polygon2 star(double a, double b, int n, double phase = 0.0, int samples = 2000)
{
    Polygon2 p;
    for (int k = 0; k < samples; ++k) {
        const double t = 2 * kPi * k / samples;
        const double r = a + b * std::cos(n * t + phase);
        p.emplace_back(r * std::cos(t), r * std::sin(t));
    }
    return p;
}
/// A profile of `rays` rays with r(k, theta) (NaN: no hit).
template <class R>
RadialProfile profile_of(int rays, R r)
{
    RadialProfile p;
    for (int k = 0; k < rays; ++k) p.r.push_back(r(k, 2 * kPi * k / rays));
    return p;
}
} // namespace

class TestMetrics : public QObject {
    Q_OBJECT
private slots:
    void drape_coefficient_of_circles()
    {
        const double R1 = 0.15, R2 = 0.075;
        QVERIFY(std::abs(drape_metrics(star(R1, 0, 1), R1, R2).drape_coefficient_percent - 100.0) < 0.01);
        QVERIFY(std::abs(drape_metrics(star(R2, 0, 1), R1, R2).drape_coefficient_percent) < 0.01);
        const double r = 0.11;
        const double expect = (r * r - R2 * R2) / (R1 * R1 - R2 * R2) * 100;
        QVERIFY(std::abs(drape_metrics(star(r, 0, 1), R1, R2).drape_coefficient_percent - expect) < 0.01);
        QCOMPARE(drape_metrics(star(r, 0, 1), R1, R2).node_count, 0);
    }

    void star_area_nodes_and_fourier_data()
    {
        QTest::addColumn<int>("n");
        QTest::addColumn<double>("b");
        for (int n : {3, 4, 5, 6, 7, 8, 9, 10, 12}) QTest::newRow(qPrintable(QString("%1 nodes").arg(n))) << n << 0.012;
        QTest::newRow("shallow 6") << 6 << 0.003;
    }
    void star_area_nodes_and_fourier()
    {
        QFETCH(int, n);
        QFETCH(double, b);
        const double a = 0.11, R1 = 0.15, R2 = 0.075;
        const DrapeMetrics m = drape_metrics(star(a, b, n, 0.3), R1, R2);
        const double area = kPi * (a * a + b * b / 2);
        QVERIFY(std::abs(m.shadow_area_m2 - area) < 1e-5 * area);
        QCOMPARE(m.node_count, n);
        QVERIFY(std::abs(m.fourier.a0 - a) < 1e-5);
        QVERIFY(std::abs(m.fourier.magnitude(n) - b) < 1e-4);
        for (double amp : m.node_amplitudes_m) QVERIFY(std::abs(amp - b) < 1e-4);
        // Crests at theta = (2 pi k - 0.3) / n.
        for (double th : m.node_angles_rad) {
            const double u = std::fmod(th * n + 0.3, 2 * kPi);
            QVERIFY(std::min(u, 2 * kPi - u) < 0.05 * n);
        }
    }

    void noise_does_not_make_nodes()
    {
        // Pixel-level noise on a circle is not a fold.
        std::mt19937 rng(4);
        std::normal_distribution<double> N(0, 0.3e-3);
        Polygon2 p = star(0.11, 0, 1);
        for (auto& q : p) q *= 1 + N(rng) / 0.11;
        QCOMPARE(drape_metrics(p, 0.15, 0.075).node_count, 0);
        // ... but five real folds on the same noise are.
        Polygon2 s = star(0.11, 0.01, 5);
        for (auto& q : s) q *= 1 + N(rng) / 0.11;
        QCOMPARE(drape_metrics(s, 0.15, 0.075).node_count, 5);
    }

    void choose_harmonics_reaches_noise()
    {
        std::mt19937 rng(8);
        std::normal_distribution<double> N(0, 0.3e-3);
        const RadialProfile p = profile_of(360, [&](int, double t) {
            return 0.1 + 0.008 * std::cos(6 * t) + 0.003 * std::sin(2 * t) + 0.0015 * std::cos(11 * t + 1) + N(rng);
        });
        const int K = choose_harmonics(p, 0.3e-3);
        QVERIFY2(K >= 11 && K <= 16, qPrintable(QString("chose %1 harmonics").arg(K)));
        const FourierSeries s = fourier_fit(p, K);
        QVERIFY(fourier_residual_rms(p, s) < 0.35e-3);
        QVERIFY(std::abs(s.magnitude(6) - 0.008) < 1e-4);
    }

    void fourier_fit_ignores_missing_rays()
    {
        const RadialProfile p = profile_of(360, [](int k, double t) {
            return k % 7 == 0 ? std::numeric_limits<double>::quiet_NaN() : 0.1 + 0.01 * std::cos(4 * t);
        });
        QVERIFY(!p.complete());
        const FourierSeries s = fourier_fit(p, 8);
        QVERIFY(std::abs(s.a0 - 0.1) < 1e-12 && std::abs(s.magnitude(4) - 0.01) < 1e-12);
    }

    // The nested fits (one basis for every K) against a reference solved here
    // by QR on an explicit sin/cos design matrix, on a profile with gaps, up to
    // the 100 harmonics the contour levels try; and evaluate()'s rotation
    // recurrence against std::cos/std::sin at harmonic 100.
    void nested_fourier_fits_match_a_reference()
    {
        std::mt19937 rng(3);
        std::normal_distribution<double> N(0, 0.5e-3);
        const RadialProfile p = profile_of(720, [&](int k, double t) {
            const bool gap = (k > 100 && k < 106) || k % 11 == 0; // a wider gap leaves 100 harmonics undetermined
            return gap ? std::numeric_limits<double>::quiet_NaN() : 0.1 + 0.01 * std::cos(5 * t) + 0.002 * std::sin(17 * t) + N(rng);
        });
        const FourierLeastSquares lsq(p, 100);
        QCOMPARE(lsq.max_harmonics(), 100);
        std::vector<int> rows;
        for (int k = 0; k < p.size(); ++k)
            if (!std::isnan(p.r[static_cast<std::size_t>(k)])) rows.push_back(k);
        for (int K : {0, 1, 7, 40, 100}) {
            Eigen::MatrixXd A(static_cast<Eigen::Index>(rows.size()), 2 * K + 1);
            Eigen::VectorXd y(A.rows());
            for (Eigen::Index i = 0; i < A.rows(); ++i) {
                const double t = p.theta(rows[static_cast<std::size_t>(i)]);
                A(i, 0) = 1;
                for (int h = 1; h <= K; ++h) A(i, 2 * h - 1) = std::cos(h * t), A(i, 2 * h) = std::sin(h * t);
                y(i) = p.r[static_cast<std::size_t>(rows[static_cast<std::size_t>(i)])];
            }
            const Eigen::VectorXd c = A.colPivHouseholderQr().solve(y);
            const FourierSeries s = lsq.fit(K);
            QCOMPARE(s.harmonics(), K);
            QVERIFY2(std::abs(s.a0 - c(0)) < 1e-10, qPrintable(QString("K %1: a0 %2 vs %3").arg(K).arg(s.a0, 0, 'g', 15).arg(c(0), 0, 'g', 15)));
            for (int h = 1; h <= K; ++h)
                QVERIFY2(std::abs(s.a[static_cast<std::size_t>(h - 1)] - c(2 * h - 1)) < 1e-10 && std::abs(s.b[static_cast<std::size_t>(h - 1)] - c(2 * h)) < 1e-10,
                         qPrintable(QString("K %1 harmonic %2").arg(K).arg(h)));
            const double rms = std::sqrt((y - A * c).squaredNorm() / static_cast<double>(y.size()));
            QVERIFY(std::abs(lsq.residual_rms(s) - rms) < 1e-12);
            QVERIFY(std::abs(fourier_residual_rms(p, s) - rms) < 1e-12);
            const FourierSeries direct = fourier_fit(p, K);
            QVERIFY(std::abs(direct.a0 - s.a0) < 1e-12);
        }
        const FourierSeries s100 = lsq.fit(100);
        for (double t : {0.3, 2.0, 5.9}) {
            double ref = s100.a0;
            for (int h = 1; h <= 100; ++h) ref += s100.a[static_cast<std::size_t>(h - 1)] * std::cos(h * t) + s100.b[static_cast<std::size_t>(h - 1)] * std::sin(h * t);
            QVERIFY(std::abs(s100.evaluate(t) - ref) < 1e-12);
        }
        QVERIFY_THROWS_EXCEPTION(drape::ParameterError, lsq.residual_rms(FourierLeastSquares(p, 120).fit(120)));
        // choose_harmonics on the shared fits is the profile's own choice.
        QCOMPARE(choose_harmonics(lsq, 0.5e-3), choose_harmonics(p, 0.5e-3, 100));
    }

    void mesh_shadow_and_slices()
    {
        // A flat disc: its shadow is the specimen (D = 100 %).
        const ClothMesh flat = make_disc(0.30, 41);
        const DrapeMetrics m = drape_metrics(shadow_outline(flat.X, flat.F), 0.15, 0.075);
        QVERIFY2(std::abs(m.drape_coefficient_percent - 100) < 0.5, qPrintable(QString::number(m.drape_coefficient_percent)));
        // A vertical tube of radius 0.09 m from z = 0 to -0.1: the slice at any depth is the circle.
        ClothMesh tube = make_rectangle(2 * kPi * 0.09, 0.1, 73, 11);
        for (int i = 0; i < tube.vertex_count(); ++i) {
            const double t = tube.X(i, 0) / 0.09, z = -tube.X(i, 1);
            tube.X(i, 0) = 0.09 * std::cos(t);
            tube.X(i, 1) = 0.09 * std::sin(t);
            tube.X(i, 2) = z;
        }
        const RadialProfile sl = slice_profile(tube.X, tube.F, -0.05, 360);
        QVERIFY(sl.complete());
        for (double r : sl.r) QVERIFY(std::abs(r - 0.09) < 0.09 * (1 - std::cos(kPi / 72)) + 1e-9);
        QVERIFY(!slice_profile(tube.X, tube.F, -0.2, 360).complete()); // below the tube: no cut
    }

    void bad_input_throws()
    {
        QVERIFY_THROWS_EXCEPTION(drape::ParameterError, drape_metrics(star(0.1, 0, 1), 0.075, 0.15));
        QVERIFY_THROWS_EXCEPTION(drape::ParameterError, drape_metrics(Polygon2{}, 0.15, 0.075));
    }
};

QTEST_APPLESS_MAIN(TestMetrics)
#include "tst_metrics.moc"
