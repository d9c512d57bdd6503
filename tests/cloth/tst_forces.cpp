// Finite-difference checks of every force (against the energy) and of the
// exact Hessian (against the forces).
#include "engine/cloth/drape.hpp"
#include "engine/cloth/system.hpp"

#include <Eigen/Eigenvalues>
#include <QTest>

#include <numbers>
#include <random>

using namespace drape::cloth;

namespace {

/// A small draped-looking state: the sheet bent over the pedestal edge so that
/// springs are stretched and compressed, stencils bent and contacts active.
std::unique_ptr<ClothSystem> bent_disc(bool triangle_mesh, unsigned seed, double stiffening_radius = 0.0, double softening_radius = 0.0,
                                       double buckling_length = 0.0, bool bending_correction = false, bool arc_membrane = false,
                                       double peak_radius = 0.0, double compression_slack = 0.0)
{
    FabricParams p;
    p[Param::CompressionSlack] = compression_slack;
    p[Param::BendPeakRadius] = peak_radius;
    p[Param::BendStiffeningRadius] = stiffening_radius;
    p[Param::BendSofteningRadius] = softening_radius;
    p[Param::BucklingLength] = buckling_length;
    p[Param::Shear] = 35.0;
    p[Param::BendWarp] = 2e-5;
    p[Param::BendWeft] = 0.7e-5;
    ClothMesh mesh = make_disc(0.3, 11, 0.0);
    if (triangle_mesh) mesh = make_triangle_mesh(mesh.X, mesh.F, Eigen::Vector3d(1, 0.3, 0));
    ModelOptions mo;
    mo.bending_correction = bending_correction;
    mo.arc_membrane = arc_membrane;
    auto s = std::make_unique<ClothSystem>(mesh, make_model(mesh, p, mo));
    // The rim's rounding (10 mm) is larger than the deepest penetration of
    // these states (~5 mm): deeper inside, the pedestal's signed distance has
    // seams (where the nearest face changes) at which it has no gradient.
    s->add_collider(std::make_shared<PedestalCollider>(Eigen::Vector3d::Zero(), 0.075, 0.12, 0.010));
    s->add_collider(std::make_shared<SphereCollider>(Eigen::Vector3d(0.12, 0.0, -0.05), 0.03));
    s->add_collider(std::make_shared<PlaneCollider>(Eigen::Vector3d(0, 0, -0.12), Eigen::Vector3d::UnitZ()));
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> U(-1.0, 1.0);
    for (int i = 0; i < s->vertex_count(); ++i) {
        const double r = std::hypot(s->x(i, 0), s->x(i, 1));
        if (r > 0.07) { // fold the overhang down and shrink it radially (compressing hoops)
            const double t = r - 0.07;
            s->x(i, 0) *= (0.07 + 0.6 * t) / r;
            s->x(i, 1) *= (0.07 + 0.6 * t) / r;
            s->x(i, 2) = -0.8 * t;
        }
        for (int c = 0; c < 3; ++c) s->x(i, c) += 2e-3 * U(rng);
        s->x(i, 2) -= 1e-4; // some vertices slightly inside colliders
    }
    return s;
}

} // namespace

class TestForces : public QObject {
    Q_OBJECT
private slots:
    void forces_are_minus_energy_gradient_data()
    {
        QTest::addColumn<bool>("triangles");
        QTest::addColumn<double>("stiffening");
        QTest::addColumn<double>("softening");
        QTest::addColumn<double>("buckling");
        QTest::addColumn<bool>("correction");
        QTest::addColumn<bool>("arc");
        QTest::addColumn<double>("peak");
        QTest::addColumn<double>("slack");
        QTest::newRow("grid") << false << 0.0 << 0.0 << 0.0 << false << false << 0.0 << 0.0;
        QTest::newRow("triangle mesh") << true << 0.0 << 0.0 << 0.0 << false << false << 0.0 << 0.0;
        // 20 mm: the nonlinear terms dominate in the sharp bends of this state.
        QTest::newRow("grid, stiffening bending") << false << 0.02 << 0.0 << 0.0 << false << false << 0.0 << 0.0;
        QTest::newRow("triangle mesh, stiffening bending") << true << 0.02 << 0.0 << 0.0 << false << false << 0.0 << 0.0;
        QTest::newRow("grid, softening bending") << false << 0.0 << 0.02 << 0.0 << false << false << 0.0 << 0.0;
        QTest::newRow("triangle mesh, both") << true << 0.01 << 0.02 << 0.0 << false << false << 0.0 << 0.0;
        // The hoops of the folded overhang are compressed past the buckling load
        // (a buckling length of 30 mm, the mesh spacing of these states).
        QTest::newRow("grid, sub-mesh buckling") << false << 0.0 << 0.0 << 0.03 << false << false << 0.0 << 0.0;
        QTest::newRow("triangle mesh, sub-mesh buckling") << true << 0.0 << 0.0 << 0.03 << false << false << 0.0 << 0.0;
        // The stencils' fourth-order correction (30 mm cells: 300 mm^2 per stencil),
        // alone, with the material's softening, with its stiffening and with the
        // compression limit.
        QTest::newRow("grid, crest-corrected bending") << false << 0.0 << 0.0 << 0.0 << true << false << 0.0 << 0.0;
        QTest::newRow("grid, crest-corrected and softening") << false << 0.0 << 0.02 << 0.0 << true << false << 0.0 << 0.0;
        QTest::newRow("grid, crest-corrected and stiffening") << false << 0.02 << 0.0 << 0.0 << true << false << 0.0 << 0.0;
        QTest::newRow("grid, crest-corrected, sub-mesh buckling") << false << 0.0 << 0.0 << 0.03 << true << false << 0.0 << 0.0;
        // Springs that measure arcs (ModelOptions::arc_membrane), with the compression
        // limit their bent crests no longer trip, and with the crest-corrected stencils,
        // softening bending and the compression limit besides.
        QTest::newRow("grid, arc membrane") << false << 0.0 << 0.0 << 0.0 << false << true << 0.0 << 0.0;
        QTest::newRow("grid, arc membrane, sub-mesh buckling") << false << 0.0 << 0.0 << 0.03 << false << true << 0.0 << 0.0;
        QTest::newRow("grid, arc membrane, crest-corrected, softening, buckling") << false << 0.0 << 0.02 << 0.03 << true << true << 0.0 << 0.0;
        // The peaking law (bend_peak_radius_m, 20 mm): this state's sharp bends are
        // past the moment's peak, where a stencil's energy is not convex.
        QTest::newRow("grid, peaking bending") << false << 0.0 << 0.0 << 0.0 << false << false << 0.02 << 0.0;
        QTest::newRow("triangle mesh, peaking bending") << true << 0.0 << 0.0 << 0.0 << false << false << 0.02 << 0.0;
        QTest::newRow("grid, crest-corrected, peaking, stiffening") << false << 0.01 << 0.0 << 0.0 << true << false << 0.02 << 0.0;
        // Slack in compression (compression_slack 5 %: this state's hoops are shortened
        // by up to 40 %, some springs inside the slack, most past it), alone, with the
        // compression limit and arcs, and on the triangles' fibres.
        QTest::newRow("grid, slack") << false << 0.0 << 0.0 << 0.0 << false << false << 0.0 << 0.05;
        QTest::newRow("grid, arc membrane, slack, buckling") << false << 0.0 << 0.0 << 0.03 << true << true << 0.0 << 0.05;
        QTest::newRow("triangle mesh, slack, buckling") << true << 0.0 << 0.0 << 0.03 << false << false << 0.0 << 0.05;
    }
    void forces_are_minus_energy_gradient()
    {
        QFETCH(bool, triangles);
        QFETCH(double, stiffening);
        QFETCH(double, softening);
        QFETCH(double, buckling);
        QFETCH(bool, correction);
        QFETCH(bool, arc);
        QFETCH(double, peak);
        QFETCH(double, slack);
        auto s = bent_disc(triangles, 3, stiffening, softening, buckling, correction, arc, peak, slack);
        Positions f;
        s->conservative_forces(s->x, f);
        const double h = 1e-7;
        double max_err = 0, max_f = 0;
        for (int i = 0; i < s->vertex_count(); i += 3)
            for (int c = 0; c < 3; ++c) {
                Positions xp = s->x, xm = s->x;
                xp(i, c) += h;
                xm(i, c) -= h;
                const double fd = -(s->potential_energy(xp) - s->potential_energy(xm)) / (2 * h);
                max_err = std::max(max_err, std::abs(fd - f(i, c)));
                max_f = std::max(max_f, std::abs(f(i, c)));
            }
        QVERIFY(max_f > 0);
        QVERIFY2(max_err < 1e-5 * max_f, qPrintable(QString("max error %1 of max force %2").arg(max_err).arg(max_f)));
    }

    void exact_hessian_is_force_jacobian_data() { forces_are_minus_energy_gradient_data(); }
    void exact_hessian_is_force_jacobian()
    {
        QFETCH(bool, triangles);
        QFETCH(double, stiffening);
        QFETCH(double, softening);
        QFETCH(double, buckling);
        QFETCH(bool, correction);
        QFETCH(bool, arc);
        QFETCH(double, peak);
        QFETCH(double, slack);
        auto s = bent_disc(triangles, 5, stiffening, softening, buckling, correction, arc, peak, slack);
        HessianAssembler H(*s);
        H.assemble(s->x, Eigen::VectorXd(), 0.0, /*project=*/false);
        const Eigen::MatrixXd Hu = Eigen::MatrixXd(H.matrix());
        const Eigen::MatrixXd Hd = Eigen::MatrixXd(Hu.selfadjointView<Eigen::Upper>());
        const double h = 1e-7;
        double max_err = 0, max_h = Hd.cwiseAbs().maxCoeff();
        for (int i = 0; i < s->vertex_count(); i += 4)
            for (int c = 0; c < 3; ++c) {
                Positions xp = s->x, xm = s->x, fp, fm;
                xp(i, c) += h;
                xm(i, c) -= h;
                s->conservative_forces(xp, fp);
                s->conservative_forces(xm, fm);
                const Positions col = -(fp - fm) / (2 * h);
                const Eigen::Map<const Eigen::VectorXd> colv(col.data(), col.size());
                max_err = std::max(max_err, (colv - Hd.col(3 * i + c)).cwiseAbs().maxCoeff());
            }
        QVERIFY2(max_err < 1e-4 * max_h, qPrintable(QString("max error %1 of max entry %2").arg(max_err).arg(max_h)));
    }

    /// The sub-mesh buckling law: linear to half the buckling load, then
    /// saturating; energy, force and stiffness continuous (C2), the compressive
    /// force never above fc, the stiffness positive; derivatives by differences.
    void buckling_spring_law_is_smooth_and_bounded()
    {
        Spring sp{0, 1, 0.01, 200.0, 0.0, SpringKind::StretchU, 0.05};
        const double x1 = -0.5 * sp.fc / sp.k; // the transition [m]
        auto at = [&](double x) {
            double e, de, d2e;
            sp.law(sp.rest + x, e, de, d2e);
            return Eigen::Vector3d(e, de, d2e);
        };
        const double eps = 1e-9 * sp.rest;
        const Eigen::Vector3d lo = at(x1 - eps), hi = at(x1 + eps);
        // Across 2 eps the values move by their slope times 2 eps only.
        // (the old hard cap jumped by k in the stiffness).
        QVERIFY2(std::abs(lo(0) - hi(0)) < 4 * eps * sp.fc && std::abs(lo(1) - hi(1)) < 4 * eps * sp.k &&
                     std::abs(lo(2) - hi(2)) < 4 * eps * 2 * sp.k * sp.k / sp.fc,
                 qPrintable(QString("jump at the transition: %1 %2 %3").arg(lo(0) - hi(0)).arg(lo(1) - hi(1)).arg(lo(2) - hi(2))));
        for (double x : {-0.5 * sp.rest, -0.1 * sp.rest, 4 * x1, 1.5 * x1, x1, 0.5 * x1, 0.0, 0.1 * sp.rest}) {
            const Eigen::Vector3d v = at(x);
            const double h = 1e-7 * sp.rest;
            const Eigen::Vector3d p = at(x + h), m = at(x - h);
            QVERIFY2(std::abs((p(0) - m(0)) / (2 * h) - v(1)) < 1e-6 * sp.fc, qPrintable(QString("de at x = %1").arg(x)));
            QVERIFY2(std::abs((p(1) - m(1)) / (2 * h) - v(2)) < 1e-5 * sp.k, qPrintable(QString("d2e at x = %1").arg(x)));
            QVERIFY(v(1) >= -sp.fc);
            QVERIFY(v(2) > 0);
        }
        QVERIFY(std::abs(at(-0.5 * sp.rest)(1) + sp.fc) < 1e-6 * sp.fc); // deep compression: the buckling load
        QCOMPARE(at(0.002)(1), sp.k * 0.002);                             // tension: linear
        Spring slack = sp;
        slack.fc = 0; // no bending stiffness: no compressive force
        double e, de, d2e;
        slack.law(sp.rest * 0.9, e, de, d2e);
        QCOMPARE(de, 0.0);
    }

    /// Slack in compression (slack_spring_law): tension as without it; the first
    /// `slack` of shortening at kSlackStiffnessFraction of k; beyond it the law
    /// with the compression limit, shifted by the slack; energy and force
    /// continuous everywhere, derivatives by differences away from the two steps.
    void slack_spring_law_takes_up_its_slack()
    {
        Spring sp{0, 1, 0.01, 200.0, 0.0, SpringKind::StretchU, 0.05};
        sp.slack = 0.02 * sp.rest;
        const double eps = kSlackStiffnessFraction;
        auto at = [&](const Spring& s, double x) {
            double e, de, d2e;
            s.law(s.rest + x, e, de, d2e);
            return Eigen::Vector3d(e, de, d2e);
        };
        Spring plain = sp;
        plain.slack = 0;
        QCOMPARE(at(sp, 0.001), at(plain, 0.001)); // tension: unchanged
        const double a = sp.slack, x1 = -0.5 * sp.fc / sp.k - a;
        QCOMPARE(at(sp, -0.5 * a)(1), -eps * sp.k * 0.5 * a); // inside the slack: eps k
        QCOMPARE(at(sp, -0.5 * a)(2), eps * sp.k);
        // Beyond it: eps k x plus the law of x + slack.
        const Eigen::Vector3d deep = at(sp, -3 * a), shifted = at(plain, -2 * a);
        QVERIFY(std::abs(deep(1) - (-eps * sp.k * 3 * a + (1 - eps) * shifted(1))) < 1e-12 * sp.fc);
        for (double x : {0.0, -a}) { // energy and force continuous across the steps
            const double d = 1e-9 * sp.rest;
            const Eigen::Vector3d lo = at(sp, x - d), hi = at(sp, x + d);
            QVERIFY2(std::abs(lo(0) - hi(0)) < 4 * d * sp.fc && std::abs(lo(1) - hi(1)) < 4 * d * sp.k,
                     qPrintable(QString("jump at x = %1: %2 J, %3 N").arg(x).arg(lo(0) - hi(0)).arg(lo(1) - hi(1))));
        }
        for (double x : {-0.5 * sp.rest, 4 * x1, x1, -1.5 * a, -0.5 * a, 0.5 * a}) {
            const Eigen::Vector3d v = at(sp, x);
            const double h = 1e-7 * sp.rest;
            const Eigen::Vector3d p = at(sp, x + h), m = at(sp, x - h);
            QVERIFY2(std::abs((p(0) - m(0)) / (2 * h) - v(1)) < 1e-6 * sp.fc, qPrintable(QString("de at x = %1").arg(x)));
            QVERIFY2(std::abs((p(1) - m(1)) / (2 * h) - v(2)) < 1e-5 * sp.k, qPrintable(QString("d2e at x = %1").arg(x)));
            QVERIFY(v(2) > 0);
        }
        // The model sets it on the membrane's springs and fibres, as a strain of each one's rest length.
        FabricParams p;
        p[Param::CompressionSlack] = 0.01;
        const ClothMesh grid = make_disc(0.3, 11, 0.0);
        int slack_springs = 0;
        for (const Spring& s : make_model(grid, p).springs)
            if (s.kind == SpringKind::StretchU || s.kind == SpringKind::StretchV || s.kind == SpringKind::Shear) {
                QVERIFY(std::abs(s.slack - 0.01 * s.rest) < 1e-15);
                ++slack_springs;
            }
        QVERIFY(slack_springs > 100);
        const ClothMesh tri = make_triangle_mesh(grid.X, grid.F, Eigen::Vector3d(1, 0.3, 0));
        for (const MembraneFiber& f : make_model(tri, p).fibers) QVERIFY(std::abs(f.slack - 0.01 * f.rest) < 1e-15);
    }

    /// The buckling rows above check something: in those states springs are
    /// compressed past the transition.
    void bent_states_buckle_springs()
    {
        auto s = bent_disc(false, 3, 0.0, 0.0, 0.03);
        int buckled = 0;
        for (const Spring& sp : s->model().springs) {
            const double l = (s->x.row(sp.i) - s->x.row(sp.j)).norm();
            if (sp.fc > 0 && sp.k * (l - sp.rest) < -0.5 * sp.fc) ++buckled;
        }
        QVERIFY2(buckled > 20, qPrintable(QString("%1 springs past the transition").arg(buckled)));
    }

    /// The compression limit per unit width of the strip a spring stands for is
    /// the lower of the fabric's, pi^2 B / l^2, and the strip's own Euler stress
    /// pi^2 B / h^2: on grids finer than l it does not depend on the mesh (61 and
    /// 81 nodes on 300 mm: h = 5 and 3.75 mm against l = 6 mm), on coarser ones the
    /// strip between two nodes gives way first (11 and 25 nodes: 30 and 12.5 mm).
    void buckling_limit_is_the_fabrics_on_fine_meshes()
    {
        FabricParams p;
        p[Param::BendWarp] = 2e-5;
        p[Param::BendWeft] = 0.5e-5;
        p[Param::BucklingLength] = 0.006;
        const double pi2 = 9.869604401089358;
        for (int grid : {11, 25, 61, 81}) {
            const ClothMesh mesh = make_disc(0.3, grid, 0.0);
            const double h = mesh.grid.hu, l = std::max(0.006, h);
            QCOMPARE(mesh.grid.hv, h);
            const ClothModel m = make_model(mesh, p);
            int checked = 0;
            for (const Spring& sp : m.springs) {
                const double B = sp.kind == SpringKind::StretchU ? 2e-5 : 0.5e-5;
                if (sp.kind != SpringKind::StretchU && sp.kind != SpringKind::StretchV) continue;
                const double per_width = sp.fc / h;
                QVERIFY2(std::abs(per_width - pi2 * B / (l * l)) < 1e-9 * per_width,
                         qPrintable(QString("grid %1: %2 N/m, expected %3").arg(grid).arg(per_width).arg(pi2 * B / (l * l))));
                ++checked;
            }
            QVERIFY(checked > 100);
        }
        p[Param::BucklingLength] = 0; // off: the seed's membrane, linear in compression
        const ClothMesh mesh = make_disc(0.3, 25, 0.0);
        for (const Spring& sp : make_model(mesh, p).springs) QVERIFY(sp.fc < 0);
    }

    /// Springs that measure arcs read no strain where the cloth has none. The
    /// grid-41 disc (7.5 mm cells on 300 mm) rolled isometrically onto a cylinder of
    /// radius r, its axis at angle phi to the warp: every material line keeps its
    /// length, so every spring's strain should be 0. A chord reads h^3 kappa^2 / 24
    /// short (analytic: 1 - 2 r sin(h / 2r) / h); the arc (SpringArc) removes that
    /// to O((h kappa)^4), at the hem too (its least-squares weights are exact for
    /// quadratics). The compression that chords read at fold crests is what made a
    /// coarse grid drape stiffer (docs/decisions/0019-drapemeter-mesh.md).
    void arc_springs_read_no_strain_on_an_isometric_bend()
    {
        const ClothMesh mesh = make_disc(0.3, 41, 0.0);
        FabricParams p;
        ModelOptions mo;
        mo.arc_membrane = true;
        const ClothModel m = make_model(mesh, p, mo);
        int with_arc = 0;
        for (const Spring& sp : m.springs) with_arc += sp.arc >= 0;
        // All but the springs between hem nodes whose 3x3 blocks reach past the cut
        // circle (too few nodes for a curvature that does not extrapolate).
        QVERIFY2(with_arc > 0.9 * static_cast<double>(m.springs.size()),
                 qPrintable(QString("%1 of %2 springs measure arcs").arg(with_arc).arg(m.springs.size())));
        for (double r : {0.016, 0.03})
            for (double phi : {0.0, 0.3, 0.785}) {
                Positions X = mesh.X;
                const double c = std::cos(phi), sn = std::sin(phi);
                for (int i = 0; i < X.rows(); ++i) {
                    const double a = c * mesh.X(i, 0) + sn * mesh.X(i, 1), t = -sn * mesh.X(i, 0) + c * mesh.X(i, 1);
                    const double along = r * std::sin(a / r), z = r * (1 - std::cos(a / r));
                    X.row(i) << c * along - sn * t, sn * along + c * t, z;
                }
                double worst_chord = 0, worst_arc = 0;
                for (const Spring& sp : m.springs) {
                    if (sp.arc < 0) continue;
                    const double arc = m.spring_length(sp, X);
                    const double chord = (X.row(sp.i) - X.row(sp.j)).norm();
                    worst_chord = std::max(worst_chord, std::abs(chord / sp.rest - 1));
                    worst_arc = std::max(worst_arc, std::abs(arc / sp.rest - 1));
                }
                // The chord's analytic shortfall across the bend, for the warp springs' h:
                const double h = mesh.grid.hu, expected = 1 - 2 * r * std::sin(h / (2 * r)) / h;
                QVERIFY2(worst_chord > 0.9 * expected, qPrintable(QString("r %1 phi %2: chord strain %3, analytic %4").arg(r).arg(phi).arg(worst_chord).arg(expected)));
                qInfo("r %.0f mm, axis %.2f rad from the warp: worst strain %.2g (chords) -> %.2g (arcs)", 1e3 * r, phi, worst_chord, worst_arc);
                QVERIFY2(worst_arc < worst_chord / 8,
                         qPrintable(QString("r %1 phi %2: arc strain %3 against the chord's %4").arg(r).arg(phi).arg(worst_arc).arg(worst_chord)));
            }
        // A flat sheet, however moved or stretched affinely, keeps arcs equal to chords.
        Eigen::Matrix3d A;
        A << 1.1, 0.2, 0.0, -0.1, 0.9, 0.0, 0.3, 0.1, 1.0;
        const Positions Y = (mesh.X * A.transpose()).rowwise() + Eigen::RowVector3d(0.1, -0.2, 0.05);
        for (const Spring& sp : m.springs) {
            if (sp.arc < 0) continue;
            const double arc = m.spring_length(sp, Y);
            QVERIFY(std::abs(arc - (Y.row(sp.i) - Y.row(sp.j)).norm()) < 1e-12);
        }
    }

    /// Bending reaches the hem: a disc bent into a cylinder of radius R stores the
    /// continuum's 1/2 B / R^2 per unit area over the whole specimen, on every grid
    /// (make_disc moves the hem nodes onto the cut circle; the stencils through them
    /// are kernel stencils). Skipping them, as the first version did, loses a ring
    /// two cells wide: 30 % of the energy at grid 25. Any affine map of the flat
    /// disc stores nothing.
    void bending_reaches_the_hem()
    {
        FabricParams p;
        p[Param::BendWarp] = 2e-5;
        p[Param::BendWeft] = 0.5e-5;
        const double R = 0.2, radius = 0.15;
        for (int grid : {25, 41, 81}) {
            const ClothMesh mesh = make_disc(2 * radius, grid, 0.0);
            const ClothModel m = make_model(mesh, p);
            auto bending = [&](const Positions& X) {
                double e = 0;
                for (const BendStencil& st : m.bends) {
                    Eigen::Vector3d c = Eigen::Vector3d::Zero();
                    for (int i = 0; i < st.n; ++i) c += st.w[i] * X.row(st.v[i]).transpose();
                    e += 0.5 * st.k * c.squaredNorm();
                }
                return e;
            };
            Positions affine = mesh.X;
            Eigen::Matrix3d A;
            A << 1.1, 0.2, 0.0, -0.3, 0.9, 0.1, 0.4, 0.5, 1.0;
            for (int i = 0; i < affine.rows(); ++i) affine.row(i) = (A * mesh.X.row(i).transpose() + Eigen::Vector3d(0.01, 0.02, 0.03)).transpose();
            QVERIFY2(bending(affine) < 1e-12 * p[Param::BendWarp] / (R * R), qPrintable(QString("grid %1: a flat sheet bends").arg(grid)));
            for (int axis : {0, 1}) {
                Positions X = mesh.X;
                for (int i = 0; i < X.rows(); ++i) {
                    const double s = mesh.uv(i, axis);
                    X(i, axis) = R * std::sin(s / R);
                    X(i, 2) = R * (1 - std::cos(s / R));
                }
                const double B = axis == 0 ? p[Param::BendWarp] : p[Param::BendWeft];
                const double expected = 0.5 * B / (R * R) * std::numbers::pi * radius * radius;
                const double got = bending(X);
                QVERIFY2(std::abs(got / expected - 1) < 0.03,
                         qPrintable(QString("grid %1, bend along %2: %3 of the continuum's energy").arg(grid).arg(axis).arg(got / expected)));
            }
            // A twist z = kappa u v: the twist term alone, 2 Bt kappa^2 / 2 per unit
            // area with Bt = sqrt(Bu Bv), over the whole disc (the twist stencils of
            // hem cells too, on every side of the disc).
            {
                const double kappa = 1.0 / R;
                Positions X = mesh.X;
                for (int i = 0; i < X.rows(); ++i) X(i, 2) = kappa * mesh.X(i, 0) * mesh.X(i, 1);
                const double Bt = std::sqrt(p[Param::BendWarp] * p[Param::BendWeft]);
                const double expected = Bt * kappa * kappa * std::numbers::pi * radius * radius;
                const double got = bending(X);
                qInfo("grid %d: twist energy %.4f of the continuum's", grid, got / expected);
                // The cells cut by the hem that lack a node (a triangle of a cell) carry no
                // twist stencil: 6 % of the disc at grid 25, less on finer grids.
                QVERIFY2(std::abs(got / expected - 1) < (grid < 41 ? 0.08 : 0.03),
                         qPrintable(QString("grid %1, twist: %2 of the continuum's energy").arg(grid).arg(got / expected)));
            }
        }
    }

    /// A fold crest about one cell in radius (grid 41 on 300 mm: 7.5 mm cells; a
    /// cylinder of radius 8 mm, the crests of the cotton starter at grid 81): the
    /// plain second differences store 14 % too little bending energy along the grid,
    /// the corrected stencils (ModelOptions::bending_correction) within 5 %; both
    /// converge to the continuum under refinement (grid 81), the corrected ones at
    /// fourth order - along the grid, and the twist (cell) stencils at 45 degrees.
    void bending_correction_keeps_a_sharp_crest()
    {
        FabricParams p;
        p[Param::BendWarp] = 2e-5;
        p[Param::BendWeft] = 2e-5; // isotropic: the cylinder's energy B / (2 R^2) in every direction
        const double R = 0.008, radius = 0.15;
        double err[2][2][2];  // [grid 41 | 81][plain | corrected][along the grid | 45 degrees]
        double twist[2][2];   // [grid][plain | corrected]: the on-grid cell stencils alone at 45 degrees
        for (int gi = 0; gi < 2; ++gi) {
            const int grid = gi == 0 ? 41 : 81;
            const ClothMesh mesh = make_disc(2 * radius, grid, 0.0);
            for (int corr = 0; corr < 2; ++corr) {
                ModelOptions mo;
                mo.bending_correction = corr == 1;
                const ClothModel m = make_model(mesh, p, mo);
                // The bending energy of ClothSystem::potential_energy: the system's with
                // the stencils `keep` selects minus the same system's without any.
                ClothModel none = m, cells = m;
                none.bends.clear();
                cells.bends.clear();
                const double hh = mesh.grid.hu * mesh.grid.hv;
                for (const BendStencil& b : m.bends)
                    if (b.n == 4 && std::abs(std::abs(b.w[0]) * hh - 1) < 1e-9 && std::abs(std::abs(b.w[3]) * hh - 1) < 1e-9) cells.bends.push_back(b);
                const ClothSystem all_s(mesh, m), none_s(mesh, none), cells_s(mesh, cells);
                for (int dir = 0; dir < 2; ++dir) {
                    const double phi = dir == 0 ? 0.0 : std::numbers::pi / 4;
                    const Eigen::Vector2d a(std::cos(phi), std::sin(phi)), t(-a.y(), a.x());
                    Positions X = mesh.X;
                    for (int i = 0; i < X.rows(); ++i) {
                        const Eigen::Vector2d uv = mesh.uv.row(i).transpose();
                        const double sa = uv.dot(a), st = uv.dot(t); // across the axis, along it
                        const Eigen::Vector2d in = R * std::sin(sa / R) * a + st * t;
                        X.row(i) << in.x(), in.y(), R * (1 - std::cos(sa / R));
                    }
                    const double e = all_s.potential_energy(X) - none_s.potential_energy(X);
                    const double expected = 0.5 * p[Param::BendWarp] / (R * R) * std::numbers::pi * radius * radius;
                    err[gi][corr][dir] = e / expected - 1;
                    qInfo("grid %d, %s, %s: %.3f of the continuum's energy", grid, corr ? "corrected" : "plain", dir ? "45 degrees" : "along warp",
                          e / expected);
                    if (dir == 1) {
                        // Each cell stencil stands for hu hv at 2 Bt kappa_uv^2 / 2 per unit area,
                        // kappa_uv = kappa / 2 at 45 degrees (Bt = B here).
                        const double et = cells_s.potential_energy(X) - none_s.potential_energy(X);
                        const double expected_t = static_cast<double>(cells.bends.size()) * hh * p[Param::BendWarp] * 0.25 / (R * R);
                        twist[gi][corr] = et / expected_t - 1;
                        qInfo("grid %d, %s, the %zu cell stencils at 45 degrees: %.4f of the continuum's twist energy", grid,
                              corr ? "corrected" : "plain", cells.bends.size(), et / expected_t);
                    }
                }
            }
        }
        QVERIFY(err[0][0][0] < -0.10);          // plain, grid 41, along the grid: > 10 % short
        QVERIFY(std::abs(err[0][1][0]) < 0.05); // corrected: within 5 %
        for (int corr = 0; corr < 2; ++corr)
            for (int dir = 0; dir < 2; ++dir) QVERIFY(std::abs(err[1][corr][dir]) < std::abs(err[0][corr][dir]));
        // Fourth order against second: halving h cuts the plain error by about 4, the
        // corrected one by about 16 (along the grid; the twist stencils at 45 degrees).
        QVERIFY(std::abs(err[1][1][0]) < 0.25 * std::abs(err[1][0][0]));
        QVERIFY(std::abs(twist[0][1]) < 0.25 * std::abs(twist[0][0]));
        QVERIFY(std::abs(twist[1][1]) < 0.125 * std::abs(twist[0][1]));
    }

    /// The states above have mesh edges cutting the pedestal rim and the sphere
    /// between their end points, so the checks cover edge contact too.
    void bent_states_exercise_edge_contact()
    {
        for (unsigned seed : {3u, 5u}) {
            auto s = bent_disc(false, seed);
            const double with_edges = s->potential_energy(s->x);
            s->model().edge_contact = false;
            const double vertices_only = s->potential_energy(s->x);
            QVERIFY2(with_edges > vertices_only, qPrintable(QString("seed %1: no edge in contact").arg(seed)));
        }
    }

    /// Along a path through a drape's rest state, mesh edges enter and leave
    /// contact with the pedestal rim and their deepest points cross the ends
    /// and the rim's curvature seams. The energy must stay C1 there (a jump or
    /// a kink stalls the static solver's line search: a limp drape at grid 25
    /// stuck for 1000 Newton iterations): every step's energy change matches
    /// the trapezoid rule on the forces to third order.
    void energy_is_smooth_along_a_path()
    {
        FabricParams p;
        p[Param::BendWarp] = p[Param::BendWeft] = 3e-7;
        p[Param::Shear] = 10;
        p[Param::AreaDensity] = 0.2;
        DrapeSetup setup;
        setup.grid = 25;
        auto s = make_drape_system(p, setup);
        RestOptions ro;
        ro.residual = 1e-4;
        run_to_rest(*s, ro);
        std::mt19937 rng(7);
        std::normal_distribution<double> N(0, 1);
        Positions d(s->vertex_count(), 3);
        for (int i = 0; i < d.size(); ++i) d.data()[i] = N(rng);
        d *= 1e-3 / d.cwiseAbs().maxCoeff(); // every vertex moves up to 1 mm over the path
        const int steps = 4000;
        const double h = 1.0 / steps;
        Positions X = s->x, f0, f1;
        s->conservative_forces(X, f0);
        double E0 = s->potential_energy(X), worst = 0, scale = 0;
        int worst_step = -1, events = 0;
        std::vector<int> in_contact = s->edges_in_contact(X);
        for (int k = 0; k < steps; ++k) {
            const Positions Y = X + h * d;
            s->conservative_forces(Y, f1);
            const double E1 = s->potential_energy(Y);
            const double work = 0.5 * h * ((f0 + f1).cwiseProduct(d)).sum();
            const double err = std::abs(E1 - E0 + work);
            scale = std::max(scale, std::abs(work));
            if (err > worst) worst = err, worst_step = k;
            std::vector<int> now = s->edges_in_contact(Y);
            if (now != in_contact) ++events;
            in_contact = std::move(now);
            X = Y;
            f0 = f1;
            E0 = E1;
        }
        qInfo("%d steps changed the set of edges in contact; worst step error %.3g J of step work up to %.3g J (step %d)", events, worst, scale,
              worst_step);
        QVERIFY2(events >= 5, "the path must cross edge-contact events");
        QVERIFY2(worst < 1e-3 * scale, qPrintable(QString("energy step error %1 J at step %2 (work per step up to %3 J)").arg(worst).arg(worst_step).arg(scale)));
    }

    /// The case that stalled the solver, built by hand: one edge hangs over the
    /// pedestal rim (rounded 0.5 mm) from an end point pressed 0.05 mm into the
    /// top; the other end rises until the edge's deepest point leaves through
    /// the pressed end. The energy must not jump (the vertex contact takes
    /// over) nor kink. (Deeper than the rounding, the signed distance inside the
    /// pedestal has seams where the nearest face changes; no path goes there.)
    void edge_contact_hands_over_to_the_vertex_smoothly()
    {
        FabricParams p;
        ClothMesh mesh = make_disc(0.3, 5, 0.0);
        auto s = std::make_unique<ClothSystem>(mesh, make_model(mesh, p));
        const double R = 0.075;
        s->add_collider(std::make_shared<PedestalCollider>(Eigen::Vector3d::Zero(), R, 0.12, 0.5e-3));
        const auto e0 = s->edges().front();
        const int a = e0[0], b = e0[1];
        for (int i = 0; i < s->vertex_count(); ++i) s->x.row(i) = Eigen::RowVector3d(0.3 * i, 0.5, 0.05); // far from the pedestal
        s->x.row(a) = Eigen::RowVector3d(R - 2e-3, 0, -0.05e-3);
        const int steps = 2000;
        const double z0 = -1.2e-3, z1 = 0.5e-3, h = (z1 - z0) / steps;
        auto place = [&](double z) {
            Positions X = s->x;
            X.row(b) = Eigen::RowVector3d(R + 2e-3, 0, z);
            return X;
        };
        Positions f0, f1;
        Positions X = place(z0);
        s->conservative_forces(X, f0);
        double E0 = s->potential_energy(X), worst = 0, scale = 0;
        bool had_contact = false, lost_contact = false;
        for (int k = 0; k < steps; ++k) {
            const Positions Y = place(z0 + (k + 1) * h);
            s->conservative_forces(Y, f1);
            const double E1 = s->potential_energy(Y);
            const double work = 0.5 * h * (f0(b, 2) + f1(b, 2));
            worst = std::max(worst, std::abs(E1 - E0 + work));
            scale = std::max(scale, std::abs(work));
            const bool c = !s->edges_in_contact(Y).empty();
            had_contact |= c;
            lost_contact |= had_contact && !c;
            f0 = f1;
            E0 = E1;
        }
        qInfo("worst step error %.3g J of step work up to %.3g J", worst, scale);
        QVERIFY2(had_contact && lost_contact, "the path must take the edge into and out of contact");
        QVERIFY2(worst < 1e-3 * scale, qPrintable(QString("energy step error %1 J (work per step up to %2 J)").arg(worst).arg(scale)));
    }

    void projected_hessian_is_positive_semidefinite_data()
    {
        QTest::addColumn<bool>("triangles");
        QTest::addColumn<double>("stiffening");
        QTest::addColumn<double>("softening");
        QTest::addColumn<double>("buckling");
        QTest::addColumn<bool>("arc");
        QTest::addColumn<double>("peak");
        QTest::newRow("linear bending") << false << 0.0 << 0.0 << 0.0 << false << 0.0;
        QTest::newRow("stiffening bending") << false << 0.02 << 0.0 << 0.0 << false << 0.0;
        QTest::newRow("softening bending") << false << 0.0 << 0.02 << 0.0 << false << 0.0;
        // The membrane fibres of a triangle mesh, compressed in the folded overhang.
        QTest::newRow("triangle mesh") << true << 0.0 << 0.0 << 0.0 << false << 0.0;
        QTest::newRow("triangle mesh, sub-mesh buckling") << true << 0.0 << 0.0 << 0.03 << false << 0.0;
        QTest::newRow("grid, arc membrane, sub-mesh buckling") << false << 0.0 << 0.0 << 0.03 << true << 0.0;
        // Stencils bent past the peaking law's peak: not convex, projected.
        QTest::newRow("peaking bending") << false << 0.0 << 0.0 << 0.0 << false << 0.02;
    }
    void projected_hessian_is_positive_semidefinite()
    {
        QFETCH(bool, triangles);
        QFETCH(double, stiffening);
        QFETCH(double, softening);
        QFETCH(double, buckling);
        QFETCH(bool, arc);
        QFETCH(double, peak);
        auto s = bent_disc(triangles, 7, stiffening, softening, buckling, false, arc, peak);
        HessianAssembler H(*s);
        H.assemble(s->x, Eigen::VectorXd(), 0.0, /*project=*/true);
        const Eigen::MatrixXd Hd = Eigen::MatrixXd(Eigen::MatrixXd(H.matrix()).selfadjointView<Eigen::Upper>());
        Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(Hd);
        QVERIFY(es.eigenvalues().minCoeff() > -1e-8 * es.eigenvalues().maxCoeff());
    }

    void damping_forces_match_damping_matrix_data()
    {
        QTest::addColumn<bool>("triangles");
        QTest::newRow("grid") << false;
        QTest::newRow("triangle mesh") << true;
        QTest::newRow("grid, arc membrane") << false; // dashpots along the chords of arc springs
    }
    void damping_forces_match_damping_matrix()
    {
        // The implicit integrator uses D (dashpots + air) from the assembler; the
        // explicit ones use the damping forces. They must agree: f = -D v.
        QFETCH(bool, triangles);
        const bool arc = QByteArray(QTest::currentDataTag()).contains("arc");
        auto s = bent_disc(triangles, 9, 0.0, 0.0, 0.0, false, arc);
        std::mt19937 rng(1);
        std::normal_distribution<double> N(0, 0.1);
        Positions V(s->vertex_count(), 3);
        for (int i = 0; i < V.size(); ++i) V.data()[i] = N(rng);
        Positions f = Positions::Zero(V.rows(), 3);
        s->add_damping_forces(s->x, V, f);
        HessianAssembler Hk(*s), Hkd(*s);
        Hk.assemble(s->x, Eigen::VectorXd(), 0.0, false);
        Hkd.assemble(s->x, Eigen::VectorXd(), 1.0, false);
        const Eigen::MatrixXd D = Eigen::MatrixXd(Eigen::MatrixXd(Hkd.matrix() - Hk.matrix()).selfadjointView<Eigen::Upper>());
        const Eigen::Map<const Eigen::VectorXd> v(V.data(), V.size()), fv(f.data(), f.size());
        const Eigen::VectorXd Dv = D * v;
        QVERIFY((Dv + fv).cwiseAbs().maxCoeff() < 1e-9 * (1 + fv.cwiseAbs().maxCoeff()));
    }

    void collider_distance_and_normal_consistent()
    {
        // The normal is the gradient of the signed distance, the Hessian its Jacobian.
        PedestalCollider ped(Eigen::Vector3d::Zero(), 0.075, 0.12, 0.004);
        SphereCollider sph(Eigen::Vector3d(0.1, 0.2, -0.3), 0.05);
        std::mt19937 rng(11);
        std::uniform_real_distribution<double> U(-0.12, 0.12);
        for (const Collider* c : {static_cast<const Collider*>(&ped), static_cast<const Collider*>(&sph)})
            for (int k = 0; k < 200; ++k) {
                Eigen::Vector3d p(U(rng), U(rng), U(rng) * 0.5);
                if (c == &sph) p += sph.centre;
                ContactSample s0;
                c->query(p, 1e9, s0);
                const double h = 1e-7;
                Eigen::Vector3d grad;
                Eigen::Matrix3d hess;
                for (int d = 0; d < 3; ++d) {
                    Eigen::Vector3d e = Eigen::Vector3d::Zero();
                    e(d) = h;
                    ContactSample sp, sm;
                    c->query(p + e, 1e9, sp);
                    c->query(p - e, 1e9, sm);
                    grad(d) = (sp.distance - sm.distance) / (2 * h);
                    hess.col(d) = (sp.normal - sm.normal) / (2 * h);
                }
                // Skip points within 1e-6 m of a crease of the distance field (medial axis).
                if (std::abs(grad.norm() - 1) > 1e-3) continue;
                QVERIFY2((grad - s0.normal).norm() < 1e-5, qPrintable(QString("%1 at %2 %3 %4").arg(QString::fromStdString(c->kind())).arg(p.x()).arg(p.y()).arg(p.z())));
                const Eigen::Matrix3d H = c->distance_hessian(p);
                QVERIFY2((H - hess).norm() < 1e-3 * (1 + hess.norm()),
                         qPrintable(QString("%1 Hessian at %2 %3 %4").arg(QString::fromStdString(c->kind())).arg(p.x()).arg(p.y()).arg(p.z())));
            }
    }
};

QTEST_APPLESS_MAIN(TestForces)
#include "tst_forces.moc"
