// Long checks (label slow): the seed's RK4 and the static solver agree on the
// seed's Table 1 drape; D converges under grid refinement.
#include "engine/cloth/drape.hpp"

#include <QTest>

using namespace drape::cloth;

namespace {
/// The seed paper's Table 1 as grid springs (GridSprings' defaults, in SI).
Material table1(const GridSprings& g = {}) { return Material(FabricParams(), g); }
} // namespace

class TestDrapeSlow : public QObject {
    Q_OBJECT
private slots:
    void rk4_and_static_agree_on_table1()
    {
        DrapeSetup setup; // 300 / 150 mm, the seed's grid comes from the preset
        RestOptions st;
        st.integrator = Integrator::Static;
        const DrapeResult a = simulate_drape(table1(), setup, st, {BendingModel::Flexion, 2e-6});
        QVERIFY2(a.status.converged(), a.status.message.c_str());
        // Dampers do not change a rest state, and the seed's dashpots (7 N*s/m on
        // a 0.02 g particle) would hold RK4 to steps of 3e-7 s. So RK4 runs the
        // same springs and masses with light dashpots plus air damping.
        GridSprings light;
        light.d_u = light.d_v = light.d_shear = light.d_flex_u = light.d_flex_v = 2e-3;
        auto sys = make_drape_system(table1(light), setup, {BendingModel::Flexion, 2e-6});
        sys->model().air_damping = 8.0;
        RestOptions rk;
        rk.integrator = Integrator::RK4;
        rk.max_sim_time = 30;
        rk.residual = 1e-4; // explicit dynamics creep to rest; the shape is settled long before 1e-6
        rk.max_speed = 1e-4;
        DrapeResult b = measure_drape(*sys, setup);
        b.status = run_to_rest(*sys, rk);
        b = [&] { DrapeResult m = measure_drape(*sys, setup); m.status = b.status; return m; }();
        qInfo("static: D = %.2f %% (%d nodes, %ld iterations); RK4: D = %.2f %% (%d nodes, %ld steps, %s)",
              a.metrics.drape_coefficient_percent, a.metrics.node_count, a.status.newton_iterations,
              b.metrics.drape_coefficient_percent, b.metrics.node_count, b.status.steps, to_string(b.status.outcome).c_str());
        QVERIFY2(b.status.converged(), b.status.message.c_str());
        // RK4's rest state is a rest state of the static problem: Newton from it
        // barely moves it.
        RestOptions polish;
        polish.integrator = Integrator::Static;
        const DrapeResult c = simulate_drape_from(table1(), setup, b.x, polish, {BendingModel::Flexion, 2e-6});
        QVERIFY2(c.status.converged(), c.status.message.c_str());
        qInfo("RK4 state polished by Newton: D = %.2f %% (%d nodes, %ld iterations)", c.metrics.drape_coefficient_percent,
              c.metrics.node_count, c.status.newton_iterations);
        QVERIFY(std::abs(c.metrics.drape_coefficient_percent - b.metrics.drape_coefficient_percent) < 1.0);
        // A dynamic fall and the quasi-static path may buckle into different fold
        // counts (a bifurcation); with the same count they must agree on D.
        if (a.metrics.node_count == b.metrics.node_count)
            QVERIFY(std::abs(a.metrics.drape_coefficient_percent - b.metrics.drape_coefficient_percent) < 1.0);
        else
            QVERIFY(std::abs(a.metrics.drape_coefficient_percent - b.metrics.drape_coefficient_percent) < 10.0);
    }

    void drape_coefficient_converges_under_refinement()
    {
        // Mean over seeds removes the fold-pattern scatter; the change from one
        // refinement to the next must shrink.
        std::vector<double> mean;
        for (int grid : {21, 31, 45, 63}) {
            double s = 0;
            const int seeds = 3;
            for (int k = 1; k <= seeds; ++k) {
                DrapeSetup setup;
                setup.grid = grid;
                setup.seed = static_cast<std::uint64_t>(k);
                const DrapeResult r = simulate_drape(FabricParams(), setup);
                QVERIFY2(r.status.converged(), r.status.message.c_str());
                s += r.metrics.drape_coefficient_percent;
            }
            mean.push_back(s / seeds);
            qInfo("grid %d: mean D = %.2f %%", grid, mean.back());
        }
        const double d1 = std::abs(mean[1] - mean[0]), d3 = std::abs(mean[3] - mean[2]);
        QVERIFY2(d3 < 2.0, qPrintable(QString("last refinement moved D by %1 points").arg(d3)));
        QVERIFY(d3 <= d1 + 0.5);
    }
};

QTEST_APPLESS_MAIN(TestDrapeSlow)
#include "tst_drape_slow.moc"
