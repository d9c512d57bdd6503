// The fit's Jacobian from exact rest-state sensitivities (issue 15) against
// central differences of re-solved drapes, for every fitted coordinate of the
// baseline and buckling models, at a drapemeter state with the pedestal's
// contact active (every drape has it) and, for buckling, the compression limit.
#include "engine/estimate/detail/evaluator.hpp"
#include "engine/estimate/detail/uncertainty.hpp"
#include "synthetic.hpp"

#include <QTest>

#include <cmath>
#include <functional>
#include <cstdio>

using namespace drape;
using namespace drape::estimate;
using namespace drape::estimate::detail;
using cloth::Param;

namespace {

/// Relative error of J's column i against re-solves at x +- h (smooth fitted rows).
double column_error(Evaluator& ev, const Eigen::VectorXd& x, const Eigen::MatrixXd& J, int i, double h, double* norm, double* hem_fd = nullptr,
                    double* hem_j = nullptr)
{
    const auto terms = ev.best().terms;
    Eigen::VectorXd xp = x, xm = x;
    xp[i] += h;
    xm[i] -= h;
    const Evaluation ep = ev.evaluate(xp, Start::Best);
    const Evaluation em = ev.evaluate(xm, Start::Best);
    double num = 0, den = 0;
    for (std::size_t k = 0; k < terms.size(); ++k) {
        if (!terms[k].smooth || terms[k].kind == "closure") continue;
        const double fd = (ep.terms[k].simulated - em.terms[k].simulated) / (2 * h) / terms[k].sigma;
        const double jk = J(static_cast<Eigen::Index>(k), i);
        if (terms[k].kind == "hem" && hem_fd && hem_j) *hem_fd = fd, *hem_j = jk;
        num += (fd - jk) * (fd - jk);
        den += fd * fd;
    }
    *norm = std::sqrt(den);
    return std::sqrt(num / std::max(den, 1e-300));
}

/// A fabric of the tests' family: the given bendings, shear 20 N/m, 200 g/m^2.
cloth::FabricParams fabric(double warp, double weft)
{
    cloth::FabricParams p;
    p[Param::BendWarp] = warp;
    p[Param::BendWeft] = weft;
    p[Param::Shear] = 20;
    p[Param::AreaDensity] = 0.2;
    return p;
}

/// The search coordinates of `p` (each variable at its first parameter's value).
Eigen::VectorXd coords_of(const std::vector<FitVariable>& vars, const cloth::FabricParams& p)
{
    Eigen::VectorXd x(static_cast<Eigen::Index>(vars.size()));
    for (std::size_t i = 0; i < vars.size(); ++i) x[static_cast<Eigen::Index>(i)] = vars[i].to_coord(p[vars[i].params.front()]);
    return x;
}

/// Fit options of one seed on one thread at `grid` (reproducible, one drape per evaluation).
FitOptions one_seed(int grid)
{
    FitOptions o;
    o.grid = grid;
    o.seeds_per_evaluation = 1;
    o.parallel_seeds = 1;
    return o;
}

} // namespace

class TestJacobian : public QObject {
    Q_OBJECT
private slots:
    void jacobianMatchesResolvedDrapes_data()
    {
        QTest::addColumn<int>("model");
        QTest::addColumn<double>("buckling");
        QTest::addColumn<bool>("side_view_hem");
        QTest::newRow("baseline") << static_cast<int>(ModelVariant::Baseline) << 0.0 << false;
        QTest::newRow("buckling active") << static_cast<int>(ModelVariant::Buckling) << 0.02 << false;
        // The lab's hem (every set-a record's): the lowest point the side camera sees
        // in front of the pedestal, a window of angles (estimate::hem_min_over_arc).
        QTest::newRow("side-view hem") << static_cast<int>(ModelVariant::Baseline) << 0.0 << true;
    }
    void jacobianMatchesResolvedDrapes()
    {
        QFETCH(int, model);
        QFETCH(double, buckling);
        QFETCH(bool, side_view_hem);
        const int grid = 25;
        cloth::FabricParams truth = fabric(2e-5, 8e-6);
        truth[Param::BucklingLength] = buckling;
        std::vector<MeasuredDrape> recs{test::synthetic_record(truth, test::drape_setup(0.30, 0.15, grid, 7))};
        recs.front().hem_from_side_view = side_view_hem;
        FitOptions o = one_seed(grid);
        o.model = static_cast<ModelVariant>(model);
        const auto vars = fit_variables(o.model);
        cloth::FabricParams base = truth;
        base[Param::BendWarp] = 1.5e-5;
        base[Param::BendWeft] = 1.0e-5;
        base[Param::Shear] = 30;
        Evaluator ev(recs, o, vars, base); // holds references to recs and o
        const Eigen::VectorXd x = coords_of(vars, base);
        ev.objective(x, Start::Cold, Stage::Start);
        QVERIFY(ev.best().sims.front().front().status.converged());
        const Eigen::MatrixXd J = ev.jacobian(x, ev.best());
        QCOMPARE(J.rows(), static_cast<Eigen::Index>(ev.best().terms.size()));
        QCOMPARE(ev.factorisations(), 1L); // every column from the one factorisation, no re-solve
        QCOMPARE(ev.jacobian_jumps(), 0L); // a drape at rest: no feature jumps between the difference's points
        for (int i = 0; i < static_cast<int>(vars.size()); ++i) {
            double norm = 0;
            const double h = vars[static_cast<std::size_t>(i)].log_scale ? 0.01 : 0.00003;
            double hem_fd = NAN, hem_j = NAN;
            const double err = column_error(ev, x, J, i, h, &norm, &hem_fd, &hem_j);
            qInfo("%s: |dr/dc| %.3f from re-solves, relative error of the Jacobian %.4f; hem row %.3f against %.3f", vars[static_cast<std::size_t>(i)].name.c_str(),
                  norm, err, hem_j, hem_fd);
            QVERIFY2(norm > 0.05, "the coordinate moves the residual");
            QVERIFY2(err < 0.05, vars[static_cast<std::size_t>(i)].name.c_str());
            // The hem's own row (whitened by its 4 mm): within 0.1 of the re-solves'.
            QVERIFY2(std::isfinite(hem_fd) && std::abs(hem_j - hem_fd) < 0.1 + 0.05 * std::abs(hem_fd), vars[static_cast<std::size_t>(i)].name.c_str());
        }
    }

    void drapesFromFlatAreNotDrawnTwice()
    {
        // Evaluator::draw_from_flat keeps the drapes of its last points: the fit
        // grid's drapes of a candidate screened before (FlatDraw::FitGrid) are not
        // drawn again when its finer drape is asked for, nor after another point,
        // and they are the drapes a fresh evaluator draws. (The finer drape's start
        // on a kept continuation level: tst_drape.)
        const cloth::FabricParams p = fabric(2e-5, 8e-6);
        std::vector<MeasuredDrape> recs{test::synthetic_record(p, test::drape_setup(0.30, 0.15, 25, 7))};
        FitOptions o = one_seed(25);
        o.flat_check_grid = 33;
        o.random_start_seeds = 2;
        const auto vars = fit_variables(o.model);
        const Eigen::VectorXd x = coords_of(vars, p);
        Evaluator ev(recs, o, vars, p);
        QVERIFY(ev.branch_of(0) != 0); // the fit grid's drapes from flat are drawn here, not by the spread
        ev.draw_from_flat(x, Stage::FromFlat, Evaluator::FlatDraw::FitGrid);
        QCOMPARE(ev.simulations(), 2L);
        QVERIFY(!ev.cold_fine(0));
        ev.draw_from_flat(x, Stage::FromFlat);
        QCOMPARE(ev.simulations(), 3L); // the finer one only
        Evaluator fresh(recs, o, vars, p);
        fresh.draw_from_flat(x, Stage::FromFlat);
        QCOMPARE(fresh.simulations(), 3L);
        auto same = [&](const Evaluator& a) {
            QVERIFY(a.cold_fine(0) && fresh.cold_fine(0));
            QCOMPARE(a.cold_seeds(0), 2);
            QCOMPARE(a.cold_features()[0].drape_coefficient_percent, fresh.cold_features()[0].drape_coefficient_percent);
            QVERIFY(a.cold_node_counts(0) == fresh.cold_node_counts(0));
            QCOMPARE(a.cold_fine(0)->features.drape_coefficient_percent, fresh.cold_fine(0)->features.drape_coefficient_percent);
            QCOMPARE(a.cold_fine(0)->at_rest, fresh.cold_fine(0)->at_rest);
        };
        same(ev);
        Eigen::VectorXd y = x;
        y[0] += 0.1;
        ev.draw_from_flat(y, Stage::FromFlat, Evaluator::FlatDraw::FitGrid);
        QCOMPARE(ev.simulations(), 5L);
        QVERIFY(!ev.cold_fine(0)); // another point's
        QVERIFY(ev.cold_features()[0].drape_coefficient_percent != fresh.cold_features()[0].drape_coefficient_percent);
        ev.draw_from_flat(x, Stage::FromFlat); // back: every drape kept
        QCOMPARE(ev.simulations(), 5L);
        same(ev);
    }

    void aFinerDrapeFromFlatStartsOnItsSeedsLevel()
    {
        // At a fit grid that is a level of the continuation (41) the finer grid's
        // drape from flat (45: its coarse level is 41) starts from the level its
        // seed's fit-grid drape passed, kept from the screening draw. (That such a
        // start gives the full continuation's drape to the bit: tst_drape
        // continuation_from_a_kept_level_is_the_same_drape.)
        const cloth::FabricParams p = fabric(2e-5, 8e-6);
        std::vector<MeasuredDrape> recs{test::synthetic_record(p, test::drape_setup(0.30, 0.15, 25, 7))};
        FitOptions o = one_seed(cloth::kCoarsestLevel);
        o.flat_check_grid = 45;
        o.random_start_seeds = 1;
        const auto vars = fit_variables(o.model);
        const Eigen::VectorXd x = coords_of(vars, p);
        Evaluator ev(recs, o, vars, p);
        ev.draw_from_flat(x, Stage::FromFlat, Evaluator::FlatDraw::FitGrid);
        ev.draw_from_flat(x, Stage::FromFlat);
        QCOMPARE(ev.simulations(), 2L);
        QCOMPARE(ev.flat_levels_reused(), 1L);
        QVERIFY(ev.cold_fine(0) && ev.cold_fine(0)->at_rest);
        QCOMPARE(ev.cold_seeds(0), 1);
    }

    void aFeatureThatJumpsGetsNoSlope()
    {
        // The Jacobian's entries come from central differences over the step d and
        // d / 2 (whitened per coordinate); slopes_agree keeps an entry whose two
        // agree. f(t): a whitened feature along a log coordinate, d = 1e-3 decades,
        // the floor Evaluator::jacobian gives it (0.05).
        const double d = 1e-3, floor = 0.05 * 1e-3 / d;
        auto agree = [&](const std::function<double(double)>& f) {
            const double full = (f(d) - f(-d)) / (2 * d), half = (f(0.5 * d) - f(-0.5 * d)) / d;
            return slopes_agree(full, half, floor);
        };
        // Smooth: the two slopes differ by the third derivative's d^2 / 8 (0.075
        // here, against a tolerance of 0.09).
        QVERIFY(agree([](double t) { return 0.3 * t + 1e5 * t * t * t; }));
        QVERIFY(agree([](double t) { return -40 * t + 1e4 * t * t * t; }));
        // What the set-a optima showed (the metrics' discretisation): kept.
        QVERIFY(slopes_agree(0.0266, 0.0310, floor));
        QVERIFY(slopes_agree(2.037, 1.921, floor));
        // The edge: 10 % of the larger and the floor.
        QVERIFY(slopes_agree(1.0, 0.86, floor));
        QVERIFY(!slopes_agree(1.0, 0.84, floor));
        // A jump of half a sigma between the points, outside and inside the half step.
        for (double at : {0.7 * d, -0.7 * d, 0.2 * d, -0.3 * d})
            QVERIFY2(!agree([at](double t) { return 0.3 * t + (t > at ? 0.5 : 0.0); }), qPrintable(QString::number(at / d)));
        // ... and one of a thousandth of a sigma (0.8 against 0.3, ten times the floor).
        QVERIFY(!agree([](double t) { return 0.3 * t + (t > 0.6e-3 ? 1e-3 : 0.0); }));
        // A kink inside the step reads as two slopes too (-0.3 and -0.9): dropped
        // rather than averaged (rare: the argmin of a hem switching within 1e-3 decades).
        QVERIFY(!agree([](double t) { return 0.3 * t + 2 * std::abs(t - 0.3e-3); }));
        // A linear coordinate (a radius over 0..0.03 m: d = 3e-5 m) has its floor per
        // metre: 0.05 sigma over the range, 1.67 per metre - an entry of 0.5 per metre
        // that wobbles by 1 is no jump.
        QVERIFY(slopes_agree(0.5, 1.5, 0.05 * 1e-3 / 3e-5));
    }

    void aRadiusAtZeroGetsTheSecantOfSwitchingItOn()
    {
        // The stiffening radius enters the bending energy as r^2 |d|^4: at r = 0 (the
        // baseline's start) its slope is 0, and a search that only saw the slope could
        // never leave 0. Its column is the secant to a fifth of the range (6 mm), from a
        // re-solve, and it sees the stiffening the record was made with.
        const int grid = 25;
        cloth::FabricParams truth = fabric(2e-5, 8e-6);
        truth[Param::BendStiffeningRadius] = 0.01;
        const std::vector<MeasuredDrape> recs{test::synthetic_record(truth, test::drape_setup(0.30, 0.15, grid, 7))};
        FitOptions o = one_seed(grid);
        o.model = ModelVariant::Stiffening;
        const auto vars = fit_variables(o.model);
        const int ir = static_cast<int>(vars.size()) - 1;
        QCOMPARE(vars.back().params.front(), Param::BendStiffeningRadius);
        cloth::FabricParams base = truth;
        base[Param::BendStiffeningRadius] = 0;
        Evaluator ev(recs, o, vars, base);
        Eigen::VectorXd x(static_cast<Eigen::Index>(vars.size()));
        for (std::size_t i = 0; i < vars.size(); ++i)
            x[static_cast<Eigen::Index>(i)] = vars[i].to_coord(std::max(base[vars[i].params.front()], 1e-300)); // as the fit stores a start
        ev.objective(x, Start::Cold, Stage::Start);
        QVERIFY(ev.best().at_rest());
        const Eigen::MatrixXd J = ev.jacobian(x, ev.best());
        const double h = 0.2 * (vars.back().upper - vars.back().lower);
        Eigen::VectorXd xp = x;
        xp[ir] += h;
        const Evaluation ep = ev.evaluate(xp, Start::Best);
        const auto& terms = ev.best().terms;
        double norm = 0, diff = 0;
        for (std::size_t k = 0; k < terms.size(); ++k) {
            if (!terms[k].smooth || !terms[k].fitted || terms[k].kind == "closure" || !(terms[k].sigma > 0)) continue;
            const double secant = (ep.terms[k].simulated - terms[k].simulated) / h / terms[k].sigma;
            norm += secant * secant;
            diff += (secant - J(static_cast<Eigen::Index>(k), ir)) * (secant - J(static_cast<Eigen::Index>(k), ir));
        }
        qInfo("radius at 0: |secant| %.3f per m, |J column - secant| %.2e", std::sqrt(norm), std::sqrt(diff));
        QVERIFY2(std::sqrt(norm) > 1.0, "switching the stiffening on moves the residual");
        QVERIFY(std::sqrt(diff) <= 1e-9 * std::sqrt(norm));
    }

    void aDrapeNotAtRestIsNeverTheBestPoint()
    {
        // The objective keeps the best point for the next warm starts, the
        // Jacobian and the preset: a lower chi2 from drapes that did not come to
        // rest (a warm re-solve cut off at FitOptions::warm_max_newton) is no
        // drape of the model and must not replace a best point at rest.
        const int grid = 17;
        const cloth::FabricParams truth = fabric(1e-5, 1e-5);
        const std::vector<MeasuredDrape> recs{test::synthetic_record(truth, test::drape_setup(0.30, 0.15, grid, 3))};
        FitOptions o = one_seed(grid);
        o.warm_max_newton = 4; // no warm re-solve comes to rest
        const auto vars = fit_variables(o.model);
        Evaluator ev(recs, o, vars, truth);
        auto coords = [&](double bend) {
            Eigen::VectorXd x(static_cast<Eigen::Index>(vars.size()));
            for (std::size_t i = 0; i < vars.size(); ++i) {
                const Param q = vars[i].params.front();
                x[static_cast<Eigen::Index>(i)] = vars[i].to_coord(q == Param::BendWarp || q == Param::BendWeft ? bend : truth[q]);
            }
            return x;
        };
        const Eigen::VectorXd far = coords(4e-5), near = coords(1e-5);
        ev.objective(far, Start::Cold, Stage::Start);
        QVERIFY(ev.best().at_rest());
        const double chi2_far = ev.best().chi2;
        // Near the truth from the far point's rest state: cut off, not at rest.
        const double returned = ev.objective(near, Start::Best, Stage::Start);
        const double chi2_warm = ev.last().chi2;
        QVERIFY(!ev.last().at_rest());
        qInfo("chi2 at rest far from the truth %.1f, cut-off warm re-solve near it %.1f", chi2_far, chi2_warm);
        QVERIFY(chi2_warm < chi2_far); // lower, and still not taken
        QCOMPARE(ev.best().chi2, chi2_far);
        QVERIFY(ev.best_x() == far);
        QVERIFY(returned >= chi2_far); // nor offered to an optimizer as an improvement
        // The same point from flat comes to rest and is taken.
        const double chi2_cold = ev.objective(near, Start::Cold, Stage::Start);
        QVERIFY(ev.last().at_rest());
        QVERIFY(chi2_cold < chi2_far);
        QCOMPARE(ev.best().chi2, chi2_cold);
        QVERIFY(ev.best_x() == near);

        // Before any point at rest, one that is not is still the best so far
        // (a fit whose drapes never come to rest ends there, not at its start).
        FitOptions few = o;
        few.rest.max_newton = 2;
        Evaluator cut(recs, few, vars, truth);
        cut.objective(far, Start::Cold, Stage::Start);
        QVERIFY(!cut.last().at_rest());
        QVERIFY(cut.best_x() == far);
        QCOMPARE(cut.best().chi2, cut.last().chi2);
    }

    void intervalsComeOnlyFromDrapesAtRest()
    {
        // The NLopt path's intervals are central differences of warm re-solves
        // around the optimum (coordinate_sigmas). A re-solve cut off before rest
        // is no drape of the model: a difference against it is a slope of the
        // solver's path. Here no warm re-solve comes to rest, so no coordinate
        // may get a finite interval (the old code gave every one a number).
        const int grid = 17;
        const cloth::FabricParams truth = fabric(1e-5, 1e-5);
        const std::vector<MeasuredDrape> recs{test::synthetic_record(truth, test::drape_setup(0.30, 0.15, grid, 3))};
        FitOptions o = one_seed(grid);
        const auto vars = fit_variables(o.model);
        const Eigen::VectorXd x = coords_of(vars, truth);
        auto sigmas = [&](int warm_max_newton) {
            FitOptions oi = o;
            oi.warm_max_newton = warm_max_newton;
            Evaluator ev(recs, oi, vars, truth);
            ev.objective(x, Start::Cold, Stage::Start);
            [&] { QVERIFY(ev.best().at_rest()); }();
            FitResult out;
            out.chi2 = ev.best().chi2;
            out.dof = 10;
            out.correlation = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(vars.size()), static_cast<Eigen::Index>(vars.size()));
            return coordinate_sigmas(ev, vars, x, ev.best(), out);
        };
        const std::vector<double> at_rest = sigmas(500), cut = sigmas(4);
        for (std::size_t i = 0; i < vars.size(); ++i) {
            const std::string name(cloth::spec(vars[i].params.front()).key);
            qInfo("%s: sigma %.3g with the re-solves at rest, %.3g with them cut off", name.c_str(), at_rest[i], cut[i]);
            QVERIFY2(std::isfinite(at_rest[i]), name.c_str());
            QVERIFY2(!std::isfinite(cut[i]), name.c_str());
        }
    }

    void wideIntervalsSayWhetherTheDataBoundThem()
    {
        // A fitted coordinate's interval wider than a decade is "not constrained"
        // either way; the note tells one the data bound on both sides (the shear
        // hold keeps such a value) from one that runs into the fit bound.
        FitResult out;
        std::vector<FitVariable> vars = fit_variables(ModelVariant::Baseline);
        Eigen::VectorXd x(static_cast<Eigen::Index>(vars.size()));
        std::vector<double> sigma(vars.size(), 0.05);
        int shear = -1;
        for (std::size_t i = 0; i < vars.size(); ++i) {
            x[static_cast<Eigen::Index>(i)] = 0.5 * (vars[i].lower + vars[i].upper);
            if (vars[i].name == "shear_N_m") shear = static_cast<int>(i);
            for (Param q : vars[i].params) out.params[q] = vars[i].to_value(x[static_cast<Eigen::Index>(i)]);
        }
        QVERIFY(shear >= 0);
        auto note = [&](double sig) {
            sigma[static_cast<std::size_t>(shear)] = sig;
            out.estimates.clear();
            parameter_estimates(out, vars, x, sigma, true, 0.0075);
            for (const auto& e : out.estimates)
                if (e.id == Param::Shear) return e.constrained ? std::string("constrained") : e.note;
            return std::string();
        };
        const double span = vars[static_cast<std::size_t>(shear)].upper - vars[static_cast<std::size_t>(shear)].lower;
        const std::string inside = note(0.67 * span / (2 * 1.96)), open = note(1.2 * span / (2 * 1.96)); // shear: 1..1000 N/m, 3 decades
        QVERIFY2(inside.find("spans more than a decade (bounded by the data on both sides, loosely)") != std::string::npos, inside.c_str());
        QVERIFY2(open.find("spans more than a decade and runs into the fit bound") != std::string::npos, open.c_str());
    }
};

QTEST_APPLESS_MAIN(TestJacobian)
#include "tst_jacobian.moc"
