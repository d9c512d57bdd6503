// Self-contact (engine/cloth/self_contact.hpp): the distance's and the barrier's
// derivatives against central differences in every closest-feature region, the
// system's forces and exact Hessian with pairs active, the step filter, and two
// sheets dropped onto each other - apart with self-contact on, through each
// other with it off.
#include "engine/cloth/colliders.hpp"
#include "engine/cloth/model.hpp"
#include "engine/cloth/self_contact.hpp"
#include "engine/cloth/self_intersection.hpp"
#include "engine/cloth/solver.hpp"
#include "engine/cloth/system.hpp"

#include <Eigen/Geometry>
#include <QTest>

#include <cmath>

using namespace drape::cloth;
using V = Eigen::Vector3d;
using X4 = std::array<V, 4>;

namespace {

/// Relative error of an analytic gradient and Hessian of f against central
/// differences (step h) at x; returns {gradient error, Hessian error}, each
/// relative to the largest entry.
template <class F>
std::pair<double, double> check_derivatives(F&& f, const X4& x, double h)
{
    Vec12 g;
    Mat12 H;
    f(x, &g, &H);
    Vec12 gfd;
    Mat12 Hfd;
    for (int k = 0; k < 12; ++k) {
        X4 xp = x, xm = x;
        xp[static_cast<std::size_t>(k / 3)](k % 3) += h;
        xm[static_cast<std::size_t>(k / 3)](k % 3) -= h;
        Vec12 gp, gm;
        gfd(k) = (f(xp, &gp, nullptr) - f(xm, &gm, nullptr)) / (2 * h);
        Hfd.col(k) = (gp - gm) / (2 * h);
    }
    const double gs = std::max(g.cwiseAbs().maxCoeff(), 1e-300), hs = std::max(H.cwiseAbs().maxCoeff(), 1e-300);
    return {(g - gfd).cwiseAbs().maxCoeff() / gs, (H - Hfd).cwiseAbs().maxCoeff() / hs};
}

/// Two square sheets (n x n nodes, side `side` [m]) as one triangle mesh: the
/// lower one in z = z0, the upper one `gap` above it, turned by `turn` [rad]
/// about the vertical, tilted a little and shifted so no edge lines up with another.
ClothMesh two_sheets(int n, double side, double z0, double gap, double turn)
{
    const ClothMesh a = make_rectangle(side, side, n, n, V(-side / 2, -side / 2, z0));
    Positions X(2 * a.X.rows(), 3);
    Triangles F(2 * a.F.rows(), 3);
    X.topRows(a.X.rows()) = a.X;
    F.topRows(a.F.rows()) = a.F;
    const Eigen::Matrix3d R = (Eigen::AngleAxisd(turn, V::UnitZ()) * Eigen::AngleAxisd(0.005, V::UnitX())).toRotationMatrix();
    for (Eigen::Index i = 0; i < a.X.rows(); ++i) {
        V p = a.X.row(i).transpose() - V(0, 0, z0);
        p = R * (0.8 * p);
        // Shifted off the lower sheet's nodes: a point right above a node or an
        // edge sits on the border of two closest-feature regions, where the
        // distance's Hessian jumps and differences straddle the jump.
        X.row(a.X.rows() + i) = (p + V(1.37e-3, 0.71e-3, z0 + gap)).transpose();
    }
    F.bottomRows(a.F.rows()) = a.F.array() + static_cast<int>(a.X.rows());
    return make_triangle_mesh(X, F);
}

/// The sheets of two_sheets on a floor; the lower one sinks 0.05 mm into the
/// floor's contact offset (half the 1 mm thickness), so its contact is active
/// and not on the switch (where the penalty's Hessian jumps).
/// The rest shape has the sheets 8 mm apart (primitives closer than the
/// contact distance at rest are not contacts: SelfContact::apart_at_rest); the
/// system starts with them `gap` apart.
std::unique_ptr<ClothSystem> sheets_system(double gap, bool self_collision)
{
    FabricParams p;
    p[Param::Thickness] = 1e-3;
    ModelOptions o;
    o.self_collision = self_collision;
    const ClothMesh mesh = two_sheets(9, 0.10, 0.00045, 8e-3, 0.5);
    auto s = std::make_unique<ClothSystem>(mesh, make_model(mesh, p, o));
    s->x = two_sheets(9, 0.10, 0.00045, gap, 0.5).X;
    s->add_collider(std::make_shared<PlaneCollider>(V::Zero(), V::UnitZ()));
    return s;
}

} // namespace

class TestSelfContact : public QObject {
    Q_OBJECT
private slots:
    void distanceDerivativesInEveryRegion_data()
    {
        QTest::addColumn<int>("kind");
        QTest::addColumn<V>("p0");
        QTest::addColumn<V>("p1");
        QTest::addColumn<V>("p2");
        QTest::addColumn<V>("p3");
        QTest::addColumn<double>("expected");
        const V a(0, 0, 0), b(1e-2, 0, 0), c(0.2e-2, 1e-2, 0);
        // Point-triangle: face, edge and vertex regions, above and below.
        QTest::newRow("PT face") << 0 << V(0.3e-2, 0.3e-2, 0.2e-3) << a << b << c << 0.04e-6;
        QTest::newRow("PT face below") << 0 << V(0.4e-2, 0.2e-2, -0.3e-3) << a << b << c << 0.09e-6;
        QTest::newRow("PT edge") << 0 << V(0.5e-2, -0.2e-3, 0.1e-3) << a << b << c << 0.05e-6;
        QTest::newRow("PT vertex") << 0 << V(-0.2e-3, -0.1e-3, 0.2e-3) << a << b << c << 0.09e-6;
        // Edge-edge: crossing (both interior), one clamped, both clamped.
        QTest::newRow("EE interior") << 1 << V(0.2e-2, -0.5e-2, 0.3e-3) << V(0.4e-2, 0.5e-2, 0.35e-3) << V(-0.5e-2, 0.1e-2, 0)
                                     << V(0.6e-2, -0.1e-2, 0) << -1.0;
        QTest::newRow("EE end on edge") << 1 << V(0.2e-2, 0.02e-2, 0.3e-3) << V(0.3e-2, 0.8e-2, 0.9e-3) << V(-0.5e-2, 0, 0)
                                        << V(0.6e-2, 0, 0) << 0.13e-6;
        QTest::newRow("EE end to end") << 1 << V(0.7e-2, 0.1e-3, 0.2e-3) << V(1.5e-2, 0.5e-2, 0.2e-3) << V(-0.5e-2, 0, 0)
                                       << V(0.6e-2, 0, 0) << -1.0;
    }
    void distanceDerivativesInEveryRegion()
    {
        QFETCH(int, kind);
        QFETCH(V, p0);
        QFETCH(V, p1);
        QFETCH(V, p2);
        QFETCH(V, p3);
        QFETCH(double, expected);
        const auto k = kind == 0 ? ProximityPair::PointTriangle : ProximityPair::EdgeEdge;
        const X4 x{p0, p1, p2, p3};
        if (expected > 0) QVERIFY2(std::abs(pair_squared_distance(k, x) - expected) < 1e-3 * expected, qPrintable(QString::number(pair_squared_distance(k, x))));
        const auto [eg, eh] = check_derivatives([&](const X4& y, Vec12* g, Mat12* H) { return pair_squared_distance(k, y, g, H); }, x, 1e-8);
        QVERIFY2(eg < 1e-6, qPrintable(QString("gradient error %1").arg(eg)));
        QVERIFY2(eh < 1e-5, qPrintable(QString("Hessian error %1").arg(eh)));
    }

    /// The barrier: zero beyond d_hat, growing without bound towards touching,
    /// its gradient and Hessian (including the edge mollifier's terms for nearly
    /// parallel edges) the differences of its energy.
    void barrierDerivatives()
    {
        const double k = 100, dh = 1e-3;
        const X4 pt{V(0.3e-2, 0.3e-2, 0.4e-3), V(0, 0, 0), V(1e-2, 0, 0), V(0.2e-2, 1e-2, 0)};
        QCOMPARE(pair_energy(ProximityPair::PointTriangle, {V(0.3e-2, 0.3e-2, 1.1e-3), pt[1], pt[2], pt[3]}, k, dh, 0), 0.0);
        QVERIFY(pair_energy(ProximityPair::PointTriangle, {V(0.3e-2, 0.3e-2, 1e-6), pt[1], pt[2], pt[3]}, k, dh, 0) >
                pair_energy(ProximityPair::PointTriangle, pt, k, dh, 0));
        auto ept = [&](const X4& y, Vec12* g, Mat12* H) { return pair_energy(ProximityPair::PointTriangle, y, k, dh, 0, g, H); };
        auto [eg, eh] = check_derivatives(ept, pt, 1e-9);
        QVERIFY2(eg < 1e-5 && eh < 1e-4, qPrintable(QString("point-triangle %1 %2").arg(eg).arg(eh)));
        // Nearly parallel edges 0.5 mm apart: the mollifier is active (|ea x eb|^2 < 1e-3 |ea|^2 |eb|^2).
        const X4 ee{V(0, 0, 0.5e-3), V(1e-2, 0.01e-2, 0.5e-3), V(0.2e-2, 0, 0), V(0.8e-2, -0.6e-4, 0)};
        const double eps = 1e-3 * (ee[1] - ee[0]).squaredNorm() * (ee[3] - ee[2]).squaredNorm();
        const double cross = (ee[1] - ee[0]).cross(ee[3] - ee[2]).squaredNorm();
        QVERIFY2(cross < eps, qPrintable(QString("cross %1 eps %2").arg(cross).arg(eps)));
        auto eee = [&](const X4& y, Vec12* g, Mat12* H) { return pair_energy(ProximityPair::EdgeEdge, y, k, dh, eps, g, H); };
        std::tie(eg, eh) = check_derivatives(eee, ee, 1e-9);
        QVERIFY2(eg < 1e-5 && eh < 1e-4, qPrintable(QString("edge-edge mollified %1 %2").arg(eg).arg(eh)));
    }

    /// The system's forces are minus the energy's gradient and its exact Hessian
    /// the forces' Jacobian with self-contact pairs active.
    void systemForcesAndHessianWithPairsActive()
    {
        auto s = sheets_system(0.6e-3, true);
        const auto& pairs = s->self_contact_pairs(s->x);
        QVERIFY2(pairs.size() > 20, qPrintable(QString("%1 pairs").arg(pairs.size())));
        bool pt = false, ee = false;
        for (const auto& p : pairs) (p.kind == ProximityPair::PointTriangle ? pt : ee) = true;
        QVERIFY(pt && ee);
        Positions f;
        s->conservative_forces(s->x, f);
        HessianAssembler H(*s);
        H.assemble(s->x, Eigen::VectorXd(), 0.0, HessianAssembler::Projection::None);
        QVERIFY(H.revision() > 0); // the pairs coupled vertices the mesh does not
        const Eigen::MatrixXd Hu = Eigen::MatrixXd(H.matrix());
        const Eigen::MatrixXd Hd = Eigen::MatrixXd(Hu.selfadjointView<Eigen::Upper>());
        const double h = 1e-9;
        double ferr = 0, fmax = 0, herr = 0, hmax = Hd.cwiseAbs().maxCoeff();
        // Every vertex of the upper sheet that is in a pair.
        std::vector<int> in_pair;
        for (const auto& p : pairs)
            for (int v : p.v) in_pair.push_back(v);
        std::sort(in_pair.begin(), in_pair.end());
        in_pair.erase(std::unique(in_pair.begin(), in_pair.end()), in_pair.end());
        for (std::size_t n = 0; n < in_pair.size(); n += 3) {
            const int i = in_pair[n];
            for (int c = 0; c < 3; ++c) {
                Positions xp = s->x, xm = s->x, fp, fm;
                xp(i, c) += h;
                xm(i, c) -= h;
                const double fd = -(s->potential_energy(xp) - s->potential_energy(xm)) / (2 * h);
                ferr = std::max(ferr, std::abs(fd - f(i, c)));
                fmax = std::max(fmax, std::abs(f(i, c)));
                s->conservative_forces(xp, fp);
                s->conservative_forces(xm, fm);
                const Positions col = -(fp - fm) / (2 * h);
                const Eigen::Map<const Eigen::VectorXd> colv(col.data(), col.size());
                herr = std::max(herr, (colv - Hd.col(3 * i + c)).cwiseAbs().maxCoeff());
            }
        }
        QVERIFY2(ferr < 1e-4 * fmax, qPrintable(QString("force error %1 of %2").arg(ferr).arg(fmax)));
        QVERIFY2(herr < 1e-4 * hmax, qPrintable(QString("Hessian error %1 of %2").arg(herr).arg(hmax)));
    }

    /// The step filter: a step that would push the upper sheet through the lower
    /// one is cut to keep 10 % of every pair's distance; a step that moves both
    /// sheets together is not cut at all.
    void stepBoundStopsPassingThrough()
    {
        auto s = sheets_system(3e-3, true);
        const int n = s->vertex_count(), half = n / 2;
        Positions D = Positions::Zero(n, 3);
        for (int i = half; i < n; ++i) D(i, 2) = -10e-3; // upper sheet down by 10 mm: through the lower one
        const double a = s->self_contact_step_bound(s->x, D);
        QVERIFY2(a > 0.15 && a < 0.3, qPrintable(QString("alpha %1").arg(a)));
        const Positions moved = s->x + a * D;
        QCOMPARE(self_intersections(moved, s->mesh().F).pairs, 0L);
        Positions T = Positions::Zero(n, 3);
        T.col(2).setConstant(-10e-3);
        QCOMPARE(s->self_contact_step_bound(s->x, T), 1.0);
    }

    /// A mesh finer than the fabric is thick: neighbours closer than the contact
    /// distance in the rest shape are not contacts, so the flat sheet carries no
    /// barrier energy and no pre-stress.
    void neighboursAtRestAreNotContacts()
    {
        FabricParams p;
        p[Param::Thickness] = 2e-3;
        ModelOptions on;
        on.self_collision = true;
        const ClothMesh mesh = make_rectangle(0.01, 0.01, 11, 11); // 1 mm spacing, 2 mm thick
        ClothSystem s(mesh, make_model(mesh, p, on)), off(mesh, make_model(mesh, p));
        QVERIFY(s.self_contact_on());
        QCOMPARE(s.self_contact_pairs(s.x).size(), std::size_t(0));
        QCOMPARE(s.potential_energy(s.x), off.potential_energy(off.x));
    }

    /// A start where the cloth passes through itself is refused with a message,
    /// not "solved" with an infinite energy that accepts every step.
    void startThroughItselfIsReported()
    {
        auto s = sheets_system(3e-3, true);
        const int n = s->vertex_count(), half = n / 2;
        // Put one upper vertex exactly onto the lower sheet's plane, inside it.
        int inside = -1;
        for (int i = half; i < n && inside < 0; ++i)
            if (std::abs(s->x(i, 0)) < 0.02 && std::abs(s->x(i, 1)) < 0.02) inside = i;
        QVERIFY(inside >= 0);
        s->x(inside, 2) = s->x(0, 2);
        RestOptions opt;
        opt.max_newton = 50;
        const SolverStatus st = run_to_rest(*s, opt);
        QCOMPARE(st.outcome, SolverStatus::Outcome::Diverged);
        QVERIFY2(QString::fromStdString(st.message).contains("passes through itself"), st.message.c_str());
    }

    /// Two sheets dropped onto each other onto the floor: with self-contact the
    /// upper one comes to rest on the lower one, one thickness above it, with no
    /// intersecting triangles; without, it falls through it onto the floor.
    void twoSheetsDroppedStayApart()
    {
        RestOptions opt;
        opt.max_newton = 600;
        auto on = sheets_system(8e-3, true);
        const SolverStatus st = run_to_rest(*on, opt);
        QVERIFY2(st.converged(), qPrintable(QString::fromStdString(st.message)));
        const int n = on->vertex_count(), half = n / 2;
        QCOMPARE(self_intersections(on->x, on->mesh().F).pairs, 0L);
        // The upper sheet's middle rests about one thickness (1 mm) above the lower one's.
        const double lower = on->x.topRows(half).col(2).mean(), upper = on->x.bottomRows(half).col(2).mean();
        QVERIFY2(upper - lower > 0.8e-3 && upper - lower < 1.5e-3, qPrintable(QString("gap %1 m").arg(upper - lower)));
        QVERIFY(on->self_contact_pairs(on->x).size() > 0);

        auto off = sheets_system(8e-3, false);
        const SolverStatus st_off = run_to_rest(*off, opt);
        QVERIFY(st_off.converged());
        const double fell = off->x.bottomRows(half).col(2).mean() - off->x.topRows(half).col(2).mean();
        QVERIFY2(std::abs(fell) < 0.1e-3, qPrintable(QString("without self-contact the upper sheet should lie in the lower one's plane: %1 m").arg(fell)));
    }
};

QTEST_APPLESS_MAIN(TestSelfContact)
#include "tst_self_contact.moc"
