// Sensitivities of the drapemeter rest state (cloth/rest_sensitivity.hpp):
// dx/dp = H^-1 df/dp against finite differences of re-solved rest states, for
// every statically active parameter, with the pedestal contact active and with
// the compression limit active.
#include "engine/cloth/drape.hpp"
#include "engine/cloth/rest_sensitivity.hpp"
#include "engine/core/error.hpp"

#include <QTest>

#include <cmath>

using namespace drape;
using namespace drape::cloth;

namespace {

FabricParams fabric(double buckling_length, double slack = 0.0)
{
    FabricParams p;
    p[Param::AreaDensity] = 0.2;
    p[Param::BendWarp] = 1.2e-5;
    p[Param::BendWeft] = 0.6e-5;
    p[Param::Shear] = 20;
    p[Param::StretchWarp] = 800;
    p[Param::StretchWeft] = 600;
    p[Param::BucklingLength] = buckling_length;
    p[Param::CompressionSlack] = slack;
    return p;
}

DrapeSetup setup()
{
    DrapeSetup s;
    s.grid = 21;
    s.seed = 3;
    return s;
}

RestOptions tight()
{
    RestOptions o;
    o.residual = 1e-10;
    o.max_newton = 3000;
    return o;
}

/// x with its component along the turn about the axis removed.
Positions without_turn(const Positions& x, const Positions& rest)
{
    const Positions t = axis_turn(rest);
    const double tt = t.squaredNorm();
    return x - (x.cwiseProduct(t).sum() / tt) * t;
}

} // namespace

class TestRestSensitivity : public QObject {
    Q_OBJECT
private slots:
    void matchesFiniteDifferences_data()
    {
        QTest::addColumn<double>("buckling_length");
        QTest::addColumn<double>("slack");
        QTest::newRow("linear membrane") << 0.0 << 0.0;
        QTest::newRow("compression limit active") << 0.02 << 0.0;
        QTest::newRow("slack in compression") << 0.02 << 0.01;
    }
    void matchesFiniteDifferences()
    {
        QFETCH(double, buckling_length);
        QFETCH(double, slack);
        const FabricParams p = fabric(buckling_length, slack);
        const DrapeSetup s = setup();
        const DrapeResult r = simulate_drape(Material(p), s, tight());
        QVERIFY2(r.status.converged(), r.status.message.c_str());
        std::vector<Param> params = {Param::BendWarp, Param::BendWeft, Param::Shear, Param::StretchWarp, Param::AreaDensity};
        if (buckling_length > 0) params.push_back(Param::BucklingLength);
        if (slack > 0) params.push_back(Param::CompressionSlack);
        const auto sens = rest_sensitivities(Material(p), s, r.x, params);
        QCOMPARE(sens.size(), params.size());
        const auto metric = drape_metric_sensitivities(Material(p), s, r.x, params);
        QCOMPARE(metric.size(), params.size());
        // The states are contact-active: vertices rest on the disc, and with the limit
        // on, springs are compressed past half their limit.
        {
            auto sys = make_drape_system(Material(p), s);
            QVERIFY2(sys->vertex_contact_count(r.x) >= 5, qPrintable(QString("%1 vertices in contact").arg(sys->vertex_contact_count(r.x))));
            if (buckling_length > 0) {
                int buckled = 0;
                for (const Spring& sp : sys->model().springs) {
                    const double l = (r.x.row(sp.i) - r.x.row(sp.j)).norm();
                    if (sp.fc > 0 && sp.k * (l - sp.rest) < -0.5 * sp.fc) ++buckled;
                }
                QVERIFY2(buckled > 10, qPrintable(QString("%1 springs past the transition").arg(buckled)));
            }
            if (slack > 0) { // springs inside their slack and past it
                int inside = 0, past = 0;
                for (const Spring& sp : sys->model().springs) {
                    const double x = (r.x.row(sp.i) - r.x.row(sp.j)).norm() - sp.rest;
                    inside += x < 0 && x > -sp.slack;
                    past += x < -sp.slack;
                }
                QVERIFY2(inside > 10 && past > 10, qPrintable(QString("%1 springs inside the slack, %2 past it").arg(inside).arg(past)));
            }
        }
        for (std::size_t k = 0; k < sens.size(); ++k) {
            const auto& sv = sens[k];
            QCOMPARE(metric[k].param, sv.param);
            const double v = p[sv.param], h = 1e-3 * v;
            FabricParams lo = p, hi = p;
            lo[sv.param] = v - h;
            hi[sv.param] = v + h;
            const DrapeResult rl = simulate_drape_from(Material(lo), s, r.x, tight());
            const DrapeResult rh = simulate_drape_from(Material(hi), s, r.x, tight());
            QVERIFY(rl.status.converged() && rh.status.converged());
            const Positions fd = without_turn((rh.x - rl.x) / (2 * h), r.x);
            const double err = (sv.dx - fd).norm() / fd.norm();
            qInfo("%s: |dx/dp| %.3g, relative difference from finite differences %.2g, solve residual %.1g",
                  std::string(spec(sv.param).key).c_str(), fd.norm(), err, sv.solve_residual);
            QVERIFY2(err < 2e-2, qPrintable(QString("%1: relative error %2").arg(QString::fromStdString(std::string(spec(sv.param).key))).arg(err)));
            QVERIFY(sv.solve_residual < 1e-6);
            // The sensitivity of a metric: the shadow's drape coefficient along dx
            // against the re-solved states'.
            const double dD = metric[k].d_drape_coefficient_percent,
                         dD_fd = (rh.metrics.drape_coefficient_percent - rl.metrics.drape_coefficient_percent) / (2 * h);
            QVERIFY2(std::abs(dD - dD_fd) <= 2e-2 * std::abs(dD_fd) + 1e-9 * std::abs(1 / v),
                     qPrintable(QString("dD/dp %1 vs %2").arg(dD).arg(dD_fd)));
        }
    }

    void setupResponsesMatchFiniteDifferences()
    {
        // The specimen heavier on one side (the effect library's weight gradient,
        // issue 20): the response on the parameters' factorisation against
        // re-solved states at +- a small gradient. (A specimen laid off centre is
        // not checked this way: on the frictionless disc the offset drives the fold
        // pattern's turn about the axis, neutral when centred - re-solves at
        // +-0.1 mm turned the folds by different angles, 65 vs 277 Newton steps.)
        const FabricParams p = fabric(0.0);
        const DrapeSetup s = setup();
        const DrapeResult r = simulate_drape(Material(p), s, tight());
        QVERIFY2(r.status.converged(), r.status.message.c_str());
        const double size = 0.05, h = 5e-3; // the response's change; the finite-difference step
        auto changed = [&](double v) {
            DrapeSetup c = s;
            c.density_gradient.y() = v;
            return c;
        };
        const RestResponses resp = rest_responses(Material(p), s, r.x, {Param::BendWarp}, {changed(size)});
        QCOMPARE(resp.params.size(), std::size_t(1));
        QCOMPARE(resp.setups.size(), std::size_t(1));
        const DrapeResult rl = simulate_drape_from(Material(p), changed(-h), r.x, tight());
        const DrapeResult rh = simulate_drape_from(Material(p), changed(h), r.x, tight());
        QVERIFY(rl.status.converged() && rh.status.converged());
        const Positions fd = without_turn((rh.x - rl.x) / (2 * h), r.x);
        const Positions an = resp.setups.front() / size;
        const double err = (an - fd).norm() / fd.norm();
        qInfo("|dx| %.3g per unit, relative difference from finite differences %.2g, solve residual %.1g (re-solves: %ld, %ld Newton steps)",
              fd.norm(), err, resp.setup_residuals.front(), rl.status.newton_iterations, rh.status.newton_iterations);
        QVERIFY2(err < 1e-3, qPrintable(QString::number(err)));
        // Another mesh is refused.
        DrapeSetup other = s;
        other.grid = 25;
        QVERIFY_THROWS_EXCEPTION(ParameterError, rest_responses(Material(p), s, r.x, {}, {other}));
    }

    void refusesWhatItCannotDo()
    {
        const FabricParams p = fabric(0.0);
        const DrapeSetup s = setup();
        const Positions wrong = Positions::Zero(7, 3);
        QVERIFY_THROWS_EXCEPTION(ParameterError, rest_sensitivities(Material(p), s, wrong, {Param::BendWarp}));
        const DrapeResult r = simulate_drape(Material(p), s, tight());
        QVERIFY_THROWS_EXCEPTION(ParameterError, rest_sensitivities(Material(p), s, r.x, {Param::DampAir}));        // a damper
        QVERIFY_THROWS_EXCEPTION(ParameterError, rest_sensitivities(Material(p), s, r.x, {Param::BucklingLength})); // at 0
    }
};

QTEST_APPLESS_MAIN(TestRestSensitivity)
#include "tst_rest_sensitivity.moc"
