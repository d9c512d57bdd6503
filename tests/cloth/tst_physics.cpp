// Physical invariants: mass, free fall, the reaction of a pinned hanging
// sheet, energy conservation of undamped explicit integrators, stability of
// implicit Euler far beyond the explicit limit.
#include "engine/cloth/drape.hpp"
#include "engine/cloth/elastica.hpp"
#include "engine/cloth/solver.hpp"
#include "engine/core/error.hpp"

#include <Eigen/Eigenvalues>
#include <QTest>

#include <map>
#include <numbers>
#include <tuple>
#include <random>

using namespace drape::cloth;

namespace {
FabricParams undamped()
{
    FabricParams p;
    p[Param::DampStretch] = 0;
    p[Param::DampShear] = 0;
    p[Param::DampBend] = 0;
    p[Param::DampAir] = 0;
    return p;
}

/// The flat sheet X rolled isometrically onto a cylinder of radius R: arc
/// length t = (x - origin) . dir along the unit in-plane direction `dir`.
Positions rolled(const Positions& X, double R, const Eigen::Vector2d& dir, const Eigen::Vector2d& origin = Eigen::Vector2d::Zero())
{
    Positions Y = X;
    for (int i = 0; i < Y.rows(); ++i) {
        const double t = (X(i, 0) - origin.x()) * dir.x() + (X(i, 1) - origin.y()) * dir.y();
        Y(i, 0) += (R * std::sin(t / R) - t) * dir.x();
        Y(i, 1) += (R * std::sin(t / R) - t) * dir.y();
        Y(i, 2) = R * (1 - std::cos(t / R));
    }
    return Y;
}
/// A size x size square of triangles with spacing h: 0 a square lattice split
/// into triangles, 1 rows of equilateral triangles (every other row shifted by
/// half a side), 2 the split lattice with its interior vertices moved by up to
/// 30 % of the spacing.
ClothMesh test_triangles(int kind, double size, double h, const Eigen::Vector3d& warp = Eigen::Vector3d::UnitX())
{
    Positions X;
    Triangles F;
    if (kind == 1) {
        const int nx = static_cast<int>(size / h) + 1, ny = static_cast<int>(size / (h * std::sqrt(3.0) / 2)) + 1;
        X.resize(nx * ny, 3);
        for (int j = 0; j < ny; ++j)
            for (int i = 0; i < nx; ++i) X.row(i + nx * j) << i * h + (j % 2) * 0.5 * h, j * h * std::sqrt(3.0) / 2, 0.0;
        std::vector<Eigen::Vector3i> tris;
        for (int j = 0; j + 1 < ny; ++j)
            for (int i = 0; i + 1 < nx; ++i) {
                const int a = i + nx * j, b = a + 1, c = a + nx, d = c + 1;
                if (j % 2 == 0) tris.emplace_back(a, b, c), tris.emplace_back(b, d, c);
                else tris.emplace_back(a, d, c), tris.emplace_back(a, b, d);
            }
        F.resize(static_cast<Eigen::Index>(tris.size()), 3);
        for (std::size_t t = 0; t < tris.size(); ++t) F.row(static_cast<Eigen::Index>(t)) = tris[t].transpose();
    } else {
        const int n = static_cast<int>(size / h) + 1;
        const ClothMesh g = make_rectangle(size, size, n, n);
        X = g.X;
        F = g.F;
        if (kind == 2) {
            std::mt19937 rng(5);
            std::uniform_real_distribution<double> U(-0.3 * h, 0.3 * h);
            for (int i = 0; i < X.rows(); ++i)
                if (X(i, 0) > 1e-9 && X(i, 0) < size - 1e-9 && X(i, 1) > 1e-9 && X(i, 1) < size - 1e-9) X(i, 0) += U(rng), X(i, 1) += U(rng);
        }
    }
    return make_triangle_mesh(X, F, warp);
}

const char* lattice_name(int kind)
{
    return kind == 0 ? "square lattice split" : kind == 1 ? "equilateral" : kind == 2 ? "jittered" : "drapemeter rings";
}
} // namespace

class TestPhysics : public QObject {
    Q_OBJECT
private slots:
    void total_mass_is_density_times_area_data()
    {
        QTest::addColumn<int>("grid");
        QTest::newRow("11") << 11;
        QTest::newRow("31") << 31;
        QTest::newRow("80") << 80;
    }
    void total_mass_is_density_times_area()
    {
        QFETCH(int, grid);
        FabricParams p;
        p[Param::AreaDensity] = 0.237;
        const ClothMesh m = make_disc(0.30, grid);
        const ClothModel model = make_model(m, p);
        // Exactly density x the mesh's area ...
        QCOMPARE_LE(std::abs(model.total_mass() - 0.237 * m.area()), 1e-12);
        // ... and the mesh's area is the cut circle's up to the chords of its polygonal hem.
        const double circle = std::numbers::pi * 0.15 * 0.15;
        const double h = 0.30 / (grid - 1);
        QVERIFY2(std::abs(m.area() - circle) < 0.5 * 2 * std::numbers::pi * 0.15 * h * h / 0.15 + 1e-12,
                 qPrintable(QString("area %1 vs circle %2").arg(m.area()).arg(circle)));
        QCOMPARE_LE(m.area(), circle);
    }

    void free_fall_follows_gravity_data()
    {
        QTest::addColumn<QString>("integrator");
        for (const char* n : {"rk4", "midpoint", "symplectic", "euler", "implicit"}) QTest::newRow(n) << QString(n);
    }
    void free_fall_follows_gravity()
    {
        QFETCH(QString, integrator);
        const Integrator integ = parse_integrator(integrator.toStdString());
        FabricParams p = undamped();
        ClothMesh m = make_rectangle(0.1, 0.1, 6, 6);
        ClothSystem s(m, make_model(m, p));
        Stepper st(s, integ);
        const double dt = 1e-4;
        const int n = 2000;
        for (int k = 0; k < n; ++k) QVERIFY(st.step(dt));
        const double t = n * dt;
        // An unstretched sheet in free fall moves rigidly: z = -g t^2 / 2.
        const double expect = -0.5 * 9.81 * t * t;
        // Explicit Euler lags by g t dt / 2 and semi-implicit leads by it; implicit Euler likewise.
        const double tol = integ == Integrator::RK4 || integ == Integrator::Midpoint ? 1e-9 : 0.6 * 9.81 * t * dt + 1e-9;
        for (int i = 0; i < s.vertex_count(); ++i) QVERIFY2(std::abs(s.x(i, 2) - expect) <= tol, qPrintable(QString("z %1 vs %2").arg(s.x(i, 2)).arg(expect)));
        QVERIFY(std::abs(s.v(0, 2) + 9.81 * t) < 1e-6 + (integ == Integrator::ImplicitEuler ? 1e-3 : 0.0));
    }

    void pinned_sheet_reaction_equals_weight()
    {
        // A sheet hanging from its pinned top edge, at rest: the force the pins
        // must supply (minus the internal force on them) equals the weight.
        FabricParams p;
        p[Param::StretchWarp] = p[Param::StretchWeft] = 500;
        ClothMesh m = make_rectangle(0.2, 0.2, 11, 11);
        // Hang it vertically: material v runs down -z.
        for (int i = 0; i < m.vertex_count(); ++i) {
            const double y = m.X(i, 1);
            m.X(i, 1) = 0;
            m.X(i, 2) = -y;
        }
        ClothSystem s(m, make_model(m, p));
        for (int i = 0; i < m.grid.nu; ++i) s.set_pinned(m.grid.at(i, 0), true);
        RestOptions ro;
        ro.integrator = Integrator::Static;
        ro.residual = 1e-10;
        const SolverStatus st = run_to_rest(s, ro);
        QVERIFY2(st.converged(), st.message.c_str());
        Positions f;
        s.conservative_forces(s.x, f);
        Eigen::Vector3d reaction = Eigen::Vector3d::Zero();
        for (int i = 0; i < m.grid.nu; ++i) reaction -= f.row(m.grid.at(i, 0)).transpose();
        const double weight = s.model().total_mass() * 9.81;
        QVERIFY2(std::abs(reaction.z() - weight) < 1e-6 * weight, qPrintable(QString("reaction %1 N, weight %2 N").arg(reaction.z()).arg(weight)));
        QVERIFY(std::abs(reaction.x()) < 1e-6 * weight && std::abs(reaction.y()) < 1e-6 * weight);
        // The sheet stretched under its own weight: the top rows carry the most.
        QVERIFY(s.x(m.grid.at(5, 10), 2) < -0.2);
    }

    void undamped_explicit_integrators_conserve_energy_data()
    {
        QTest::addColumn<QString>("integrator");
        QTest::addColumn<double>("tolerance");
        QTest::newRow("rk4") << QString("rk4") << 1e-6;
        QTest::newRow("symplectic") << QString("symplectic") << 1e-2;
        QTest::newRow("midpoint") << QString("midpoint") << 1e-3;
    }
    void undamped_explicit_integrators_conserve_energy()
    {
        QFETCH(QString, integrator);
        QFETCH(double, tolerance);
        FabricParams p = undamped();
        p[Param::StretchWarp] = p[Param::StretchWeft] = 50;
        ClothMesh m = make_rectangle(0.1, 0.1, 6, 6);
        ClothSystem s(m, make_model(m, p));
        s.set_pinned(0, true);
        s.set_pinned(5, true);
        s.x.col(1) *= 1.05; // pre-stretched: it oscillates while it swings down
        Stepper st(s, parse_integrator(integrator.toStdString()));
        const double dt = 0.05 * st.explicit_dt_limit();
        const double e0 = s.potential_energy(s.x) + s.kinetic_energy(s.v);
        double scale = 0;
        for (int k = 0; k < 4000; ++k) {
            QVERIFY(st.step(dt));
            scale = std::max(scale, s.kinetic_energy(s.v));
        }
        const double e1 = s.potential_energy(s.x) + s.kinetic_energy(s.v);
        QVERIFY(scale > 0);
        QVERIFY2(std::abs(e1 - e0) < tolerance * scale, qPrintable(QString("drift %1 J of kinetic scale %2 J").arg(e1 - e0).arg(scale)));
    }

    void implicit_euler_stable_far_beyond_explicit_limit()
    {
        // The seed found implicit Euler unstable; ours must take steps 100x the
        // explicit limit and come to rest, not blow up.
        FabricParams p;
        DrapeSetup setup;
        setup.grid = 21;
        auto s = make_drape_system(p, setup);
        Stepper probe(*s, Integrator::RK4);
        const double dt = 100 * probe.explicit_dt_limit();
        Stepper st(*s, Integrator::ImplicitEuler);
        for (int k = 0; k < 300; ++k) QVERIFY(st.step(dt));
        QVERIFY(s->x.allFinite());
        QVERIFY2(s->kinetic_energy(s->v) < 1e-3 * s->model().total_mass() * 9.81 * 0.1,
                 qPrintable(QString("kinetic energy %1 J after %2 s").arg(s->kinetic_energy(s->v)).arg(s->time)));
        QVERIFY(s->x.col(2).minCoeff() > -0.12 - 1e-3); // above the floor
    }

    void coulomb_friction_on_an_incline()
    {
        // A small sheet on a plane tilted by 20 degrees (tan = 0.364): with
        // mu = 0.6 it sticks, with mu = 0.1 it slides with a = g (sin - mu cos).
        const double th = 20.0 * std::numbers::pi / 180.0;
        const Eigen::Vector3d n(-std::sin(th), 0, std::cos(th)), down(std::cos(th), 0, std::sin(th));
        for (double mu : {0.6, 0.1}) {
            FabricParams p;
            p[Param::Friction] = mu;
            p[Param::DampAir] = 0;
            p[Param::Thickness] = 0;
            ClothMesh m = make_rectangle(0.02, 0.02, 3, 3);
            ClothSystem s(m, make_model(m, p));
            // Lay it on the plane through the origin.
            for (int i = 0; i < s.vertex_count(); ++i) {
                const Eigen::Vector3d q = m.X(i, 0) * down + m.X(i, 1) * Eigen::Vector3d::UnitY();
                s.x.row(i) = q.transpose();
            }
            s.add_collider(std::make_shared<PlaneCollider>(Eigen::Vector3d::Zero(), n));
            const Positions x0 = s.x;
            Stepper st(s, Integrator::RK4);
            const double dt = 0.5 * st.explicit_dt_limit();
            double t = 0;
            while (t < 0.3) {
                QVERIFY(st.step(dt));
                t += dt;
            }
            const double moved = -(s.x.row(4) - x0.row(4)).dot(down.transpose()); // along the slope, downhill
            if (mu > 0.5) {
                QVERIFY2(std::abs(moved) < 2e-3, qPrintable(QString("stuck sheet moved %1 m").arg(moved)));
            } else {
                const double a = 9.81 * (std::sin(th) - mu * std::cos(th));
                QVERIFY2(std::abs(moved - 0.5 * a * t * t) < 0.05 * 0.5 * a * t * t,
                         qPrintable(QString("slid %1 m, expected %2 m").arg(moved).arg(0.5 * a * t * t)));
            }
        }
    }

    /// The static solver's lagged Coulomb friction (StaticFriction): the same
    /// sheet on the same 20-degree incline (tan = 0.364). With mu = 0.6 it comes
    /// to rest where it was laid (sticking: moved less than the 10 um sticking
    /// displacement plus the contact's sink), and the friction carries exactly
    /// the weight's component along the slope, within mu times the normal force;
    /// with mu = 0.1 or frictionless there is no rest on the slope, and the
    /// solver's path slides the sheet downhill.
    void static_friction_on_an_incline()
    {
        const double th = 20.0 * std::numbers::pi / 180.0;
        const Eigen::Vector3d n(-std::sin(th), 0, std::cos(th)), down(std::cos(th), 0, std::sin(th));
        for (double mu : {0.6, 0.1, 0.0}) {
            FabricParams p;
            p[Param::Friction] = mu;
            p[Param::Thickness] = 0;
            ClothMesh m = make_rectangle(0.02, 0.02, 3, 3);
            ClothSystem s(m, make_model(m, p));
            for (int i = 0; i < s.vertex_count(); ++i)
                s.x.row(i) = (m.X(i, 0) * down + m.X(i, 1) * Eigen::Vector3d::UnitY()).transpose();
            s.add_collider(std::make_shared<PlaneCollider>(Eigen::Vector3d::Zero(), n));
            const Positions x0 = s.x;
            RestOptions opt;
            opt.max_newton = 300;
            const SolverStatus st = run_to_rest(s, opt);
            const double moved = (s.x.row(4) - x0.row(4)).dot(-down.transpose()); // downhill
            if (mu > 0.5) {
                QVERIFY2(st.converged(), qPrintable(QString::fromStdString(st.message)));
                QVERIFY2(std::abs(moved) < 2e-5, qPrintable(QString("stuck sheet moved %1 m").arg(moved)));
                // At rest, without friction the forces on the sheet (weight, the
                // plane's normal push, the springs) leave the weight's component
                // along the slope unbalanced: that is what friction carries, and
                // it is within mu times the normal force.
                StaticFriction sf;
                s.update_static_friction(sf, s.x);
                Positions f;
                s.conservative_forces(s.x, f); // s.static_friction is unset after the solve: no friction in f
                const Eigen::Vector3d net = f.colwise().sum().transpose();
                const double W = s.model().total_mass() * 9.81, normal = sf.lambda.sum();
                QVERIFY2(std::abs(net.norm() - W * std::sin(th)) < 1e-3 * W,
                         qPrintable(QString("unbalanced %1 N, weight along the slope %2 N").arg(net.norm()).arg(W * std::sin(th))));
                QVERIFY2(std::abs(net.dot(n)) < 1e-3 * W, "the plane balances the weight's normal component");
                QVERIFY2(std::abs(normal - W * std::cos(th)) < 1e-3 * W, qPrintable(QString("normal %1 N").arg(normal)));
                QVERIFY(net.norm() <= mu * normal);
            } else {
                QVERIFY2(!st.converged() && std::abs(moved) > 5e-3,
                         qPrintable(QString("mu %1: %2, moved %3 m downhill").arg(mu).arg(QString::fromStdString(to_string(st.outcome))).arg(moved)));
            }
        }
    }

    /// The friction potential's force is minus its gradient and its Hessian the
    /// force's Jacobian, for contacts sticking (within eps of the anchor) and
    /// sliding (beyond it), by central differences.
    void static_friction_derivatives()
    {
        FabricParams p;
        p[Param::Friction] = 0.4;
        p[Param::Thickness] = 1e-3;
        ClothMesh m = make_rectangle(0.02, 0.02, 4, 4);
        ClothSystem s(m, make_model(m, p));
        s.x.col(2).array() = 0.2e-3; // inside the contact offset (0.5 mm) of the floor
        s.add_collider(std::make_shared<PlaneCollider>(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ()));
        StaticFriction sf;
        s.static_friction = &sf;
        s.update_static_friction(sf, s.x);
        QCOMPARE(sf.contacts, s.vertex_count());
        // Move every vertex from its anchor: even vertices by 3 um (sticking), odd ones by 40 um (sliding).
        for (int i = 0; i < s.vertex_count(); ++i) {
            const double r = (i % 2 ? 40e-6 : 3e-6);
            s.x(i, 0) += r * std::cos(0.7 * i);
            s.x(i, 1) += r * std::sin(0.7 * i);
            s.x(i, 2) += 0.1e-3 * std::sin(1.3 * i);
        }
        for (int i = 0; i < s.vertex_count(); ++i) {
            Eigen::Vector3d g;
            Eigen::Matrix3d H;
            const double e0 = s.static_friction_term(i, s.x, &g, &H);
            QVERIFY(e0 > 0);
            const double h = 1e-9;
            for (int c = 0; c < 3; ++c) {
                Positions xp = s.x, xm = s.x;
                xp(i, c) += h;
                xm(i, c) -= h;
                Eigen::Vector3d gp, gm;
                const double fd = (s.static_friction_term(i, xp, &gp) - s.static_friction_term(i, xm, &gm)) / (2 * h);
                QVERIFY2(std::abs(fd - g(c)) < 1e-6 * g.norm() + 1e-12, qPrintable(QString("vertex %1 gradient %2 vs %3").arg(i).arg(g(c)).arg(fd)));
                const Eigen::Vector3d col = (gp - gm) / (2 * h);
                QVERIFY2((col - H.col(c)).norm() < 1e-5 * H.norm(), qPrintable(QString("vertex %1 Hessian column %2").arg(i).arg(c)));
            }
            QVERIFY(H.selfadjointView<Eigen::Upper>().eigenvalues().minCoeff() > -1e-9 * H.norm()); // positive semidefinite
        }
        s.static_friction = nullptr;
    }

    /// Nonlinear bending. Stiffening (Param::BendStiffeningRadius r): a sheet rolled
    /// into a cylinder of radius R stores B kappa^2 / 2 (1 + r^2 kappa^2 / 2) per unit
    /// area (moment B kappa (1 + r^2 kappa^2)), so E(r) / E(0) = 1 + r^2 / (2 R^2).
    /// Softening (Param::BendSofteningRadius rho): B (sqrt(1 + rho^2 kappa^2) - 1) / rho^2
    /// (moment B kappa / sqrt(1 + rho^2 kappa^2)). Either axis; 0 = linear bending.
    void stiffening_bending_energy_follows_the_moment_law_data()
    {
        QTest::addColumn<int>("axis");
        QTest::addColumn<double>("R");
        QTest::addColumn<double>("r");
        QTest::addColumn<bool>("softening");
        QTest::newRow("stiffening, warp, R 50 mm, r 20 mm") << 0 << 0.05 << 0.02 << false;
        QTest::newRow("stiffening, weft, R 30 mm, r 10 mm") << 1 << 0.03 << 0.01 << false;
        QTest::newRow("stiffening, warp, R 20 mm, r 40 mm") << 0 << 0.02 << 0.04 << false;
        QTest::newRow("softening, warp, R 20 mm, rho 20 mm") << 0 << 0.02 << 0.02 << true;
        QTest::newRow("softening, weft, R 50 mm, rho 10 mm") << 1 << 0.05 << 0.01 << true;
    }
    void stiffening_bending_energy_follows_the_moment_law()
    {
        QFETCH(int, axis);
        QFETCH(double, R);
        QFETCH(double, r);
        QFETCH(bool, softening);
        const ClothMesh mesh = make_rectangle(0.06, 0.06, 61, 61);
        auto bending_energy = [&](double radius) {
            FabricParams p = undamped();
            p[softening ? Param::BendSofteningRadius : Param::BendStiffeningRadius] = radius;
            ClothModel model = make_model(mesh, p);
            model.gravity.setZero();
            model.springs.clear(); // rolling is isometric; keep the bending energy alone
            ClothSystem s(mesh, model);
            return s.potential_energy(rolled(mesh.X, R, axis == 0 ? Eigen::Vector2d(1, 0) : Eigen::Vector2d(0, 1)));
        };
        const double e0 = bending_energy(0.0), er = bending_energy(r);
        QVERIFY(e0 > 0);
        // Softening: (sqrt(1 + rho^2 kappa^2) - 1) / rho^2 per (kappa^2 / 2).
        const double x = r * r / (R * R);
        const double expected = softening ? 2 * (std::sqrt(1 + x) - 1) / x : 1 + x / 2;
        QVERIFY2(std::abs(er / e0 - expected) < 2e-3 * expected,
                 qPrintable(QString("E(r)/E(0) = %1, expected %2").arg(er / e0).arg(expected)));
        // And the linear part is the continuum B kappa^2 / 2 per unit area (interior of the sheet).
        FabricParams p = undamped();
        const double B = axis == 0 ? p[Param::BendWarp] : p[Param::BendWeft];
        const double area = 0.06 * 0.06;
        QVERIFY2(std::abs(e0 / (0.5 * B / (R * R) * area) - 1) < 0.05,
                 qPrintable(QString("E(0) = %1 J, continuum %2 J").arg(e0).arg(0.5 * B / (R * R) * area)));
    }

    /// Bending on a general triangle mesh (garments, imported meshes) is the
    /// orthotropic plate whatever the triangulation: a sheet rolled isometrically
    /// onto a cylinder of curvature kappa whose bend runs at angle phi to the warp
    /// stores (Bu c^4 + 2 sqrt(Bu Bv) c^2 s^2 + Bv s^4) kappa^2 / 2 per unit area,
    /// the grid model's law. Until 2026-11-30 a hinge stencil gave 0.45 B on a
    /// disc of concentric rings and 0.34..0.95 B by direction on a square lattice
    /// split into triangles (docs/decisions/0014-triangle-model-plate-and-fibres.md).
    void triangle_mesh_bending_is_the_orthotropic_plate_data()
    {
        QTest::addColumn<int>("mesh");
        QTest::addColumn<double>("phi_deg");
        for (int m = 0; m < 4; ++m)
            for (double deg : {0.0, 30.0, 45.0, 70.0, 90.0, 135.0})
                QTest::newRow(qPrintable(QString("%1, %2 deg").arg(lattice_name(m)).arg(deg)))
                    << m << deg;
    }
    void triangle_mesh_bending_is_the_orthotropic_plate()
    {
        QFETCH(int, mesh);
        QFETCH(double, phi_deg);
        const double size = 0.1, h = 0.005;
        // 3: the drapemeter's graded ring disc, 100 mm across at nominal spacing h.
        const ClothMesh m = mesh < 3 ? test_triangles(mesh, size, h)
                                     : make_ring_disc(size, static_cast<int>(size / h) + 1, RingGrading{0.02, 0.03, 0.4, 0.01});
        FabricParams p = undamped();
        p[Param::BendWarp] = 2e-5;
        p[Param::BendWeft] = 3e-6;
        ClothModel model = make_model(m, p);
        model.gravity.setZero();
        model.springs.clear(); // rolling is isometric; keep the bending energy alone
        model.fibers.clear();
        const double area = m.area();
        ClothSystem s(m, model);
        const double kappa = 2.0, R = 1 / kappa, ph = phi_deg * std::numbers::pi / 180;
        const Eigen::Vector2d dir(std::cos(ph), std::sin(ph));
        const Positions Y = rolled(m.X, R, dir, mesh < 3 ? Eigen::Vector2d(size / 2, size / 2) : Eigen::Vector2d::Zero());
        const double c2 = dir.x() * dir.x(), s2 = dir.y() * dir.y();
        const double Bphi = p[Param::BendWarp] * c2 * c2 + 2 * std::sqrt(p[Param::BendWarp] * p[Param::BendWeft]) * c2 * s2 + p[Param::BendWeft] * s2 * s2;
        const double expected = 0.5 * Bphi * kappa * kappa * area;
        const double e = s.potential_energy(Y);
        QVERIFY2(std::abs(e / expected - 1) < 0.02, qPrintable(QString("E = %1 J, plate %2 J (ratio %3)").arg(e).arg(expected).arg(e / expected)));
    }

    /// The membrane of a general triangle mesh is the grid's (warp and weft
    /// moduli Eu, Ev, shear modulus G), whatever the triangulation and however the
    /// warp lies on the mesh: affine strains in the material frame cost the
    /// continuum's energy, A Eu eps^2 / 2 along the warp, A Ev eps^2 / 2 along the
    /// weft and A G gamma^2 / 2 in shear. (The edge springs used until 2026-12-01
    /// had one isotropic modulus (Eu + Ev) / 2 and a shear stiffness near 3/8 of
    /// it, whatever G.) And compressed past the buckling load, the warp's
    /// compressive stress saturates at the Euler stress pi^2 Bu / lb^2.
    void triangle_membrane_is_the_orthotropic_sheet_data()
    {
        QTest::addColumn<int>("mesh");
        QTest::addColumn<double>("warp_deg");
        for (int m = 0; m < 3; ++m)
            for (double deg : {0.0, 30.0, 45.0, 110.0})
                QTest::newRow(qPrintable(QString("%1, warp at %2 deg").arg(lattice_name(m)).arg(deg))) << m << deg;
    }
    void triangle_membrane_is_the_orthotropic_sheet()
    {
        QFETCH(int, mesh);
        QFETCH(double, warp_deg);
        const double a = warp_deg * std::numbers::pi / 180;
        const ClothMesh m = test_triangles(mesh, 0.1, 0.005, Eigen::Vector3d(std::cos(a), std::sin(a), 0));
        FabricParams p = undamped();
        p[Param::StretchWarp] = 3000;
        p[Param::StretchWeft] = 1800;
        p[Param::Shear] = 60;
        auto membrane_energy = [&](const FabricParams& q, const Eigen::Matrix<double, 3, 2>& Fd) {
            ClothModel model = make_model(m, q);
            model.gravity.setZero();
            model.bends.clear(); // affine maps do not bend; the membrane alone
            ClothSystem s(m, model);
            Positions Y(m.vertex_count(), 3);
            for (int i = 0; i < Y.rows(); ++i) Y.row(i) = (Fd * m.uv.row(i).transpose()).transpose();
            return s.potential_energy(Y);
        };
        const double A = m.area(), eps = 1e-4;
        Eigen::Matrix<double, 3, 2> Fd = Eigen::Matrix<double, 3, 2>::Identity();
        Fd(0, 0) = 1 + eps; // along the warp (material u)
        QVERIFY(std::abs(membrane_energy(p, Fd) / (0.5 * 3000 * eps * eps * A) - 1) < 1e-3);
        Fd = Eigen::Matrix<double, 3, 2>::Identity();
        Fd(1, 1) = 1 + eps; // along the weft
        QVERIFY(std::abs(membrane_energy(p, Fd) / (0.5 * 1800 * eps * eps * A) - 1) < 1e-3);
        Fd = Eigen::Matrix<double, 3, 2>::Identity();
        Fd(0, 1) = 100 * eps; // simple shear, gamma = 0.01
        const double e_shear = membrane_energy(p, Fd), want = 0.5 * 60 * 1e-4 * A;
        QVERIFY2(std::abs(e_shear / want - 1) < 0.02, qPrintable(QString("shear energy %1 J, continuum %2 J").arg(e_shear).arg(want)));

        // Compressed along the warp by 5 % with the least shear stiffness (the
        // diagonals carry 1e-3 of the stress): the stress is the Euler stress of
        // the buckling length, not Eu eps.
        FabricParams q = p;
        q[Param::Shear] = 0.01;
        q[Param::BendWarp] = 2e-5;
        q[Param::BucklingLength] = 0.02;
        const double d = 1e-6;
        Eigen::Matrix<double, 3, 2> Fp = Eigen::Matrix<double, 3, 2>::Identity(), Fm = Fp;
        Fp(0, 0) = 0.95 + d;
        Fm(0, 0) = 0.95 - d;
        const double stress = (membrane_energy(q, Fp) - membrane_energy(q, Fm)) / (2 * d * A); // [N/m]
        const double euler = std::numbers::pi * std::numbers::pi * 2e-5 / (0.02 * 0.02);
        QVERIFY2(std::abs(-stress / euler - 1) < 0.01, qPrintable(QString("compressive stress %1 N/m, Euler %2 N/m").arg(-stress).arg(euler)));
    }

    /// The membrane's dashpots dissipate what the grid's do: a uniform stretching
    /// rate edot along the warp costs A (c_stretch + c_shear) edot^2 of power (the
    /// warp fibres c_stretch edot^2, the two diagonals 2 c_shear (edot / 2)^2 each),
    /// and along the weft the same with its own fibres; a rigid rotation costs
    /// nothing. On every triangulation, whatever the warp's direction on the mesh.
    void triangle_membrane_damping_is_the_grids()
    {
        for (int mesh = 0; mesh < 3; ++mesh) {
            const ClothMesh m = test_triangles(mesh, 0.1, 0.005, Eigen::Vector3d(std::cos(0.4), std::sin(0.4), 0));
            FabricParams p = undamped();
            p[Param::DampStretch] = 0.05;
            p[Param::DampShear] = 0.01;
            ClothModel model = make_model(m, p);
            model.bends.clear(); // the membrane's dashpots alone
            const ClothSystem s(m, model);
            // Velocities in space of the material rates: v = L (u, v) with L in the
            // material frame, mapped through the mesh's own warp and weft axes (X =
            // c + u e_u + v e_v, by least squares over the vertices).
            Eigen::MatrixXd P(m.vertex_count(), 3);
            P.col(0).setOnes();
            P.rightCols<2>() = m.uv;
            const Eigen::MatrixXd M = P.colPivHouseholderQr().solve(Eigen::MatrixXd(m.X));
            const Eigen::Vector3d eu = M.row(1).transpose(), ev = M.row(2).transpose();
            QVERIFY(std::abs(eu.norm() - 1) < 1e-9 && std::abs(ev.norm() - 1) < 1e-9 && std::abs(eu.dot(ev)) < 1e-9);
            auto power = [&](const Eigen::Matrix2d& L) {
                Positions V(m.vertex_count(), 3), f = Positions::Zero(m.vertex_count(), 3);
                for (int i = 0; i < V.rows(); ++i) {
                    const Eigen::Vector2d r = L * m.uv.row(i).transpose();
                    V.row(i) = (r.x() * eu + r.y() * ev).transpose();
                }
                s.add_damping_forces(m.X, V, f);
                return -(f.array() * V.array()).sum();
            };
            const double edot = 0.3, A = m.area();
            Eigen::Matrix2d L = Eigen::Matrix2d::Zero();
            L(0, 0) = edot;
            const double warp = power(L), want = A * (0.05 + 0.01) * edot * edot;
            QVERIFY2(std::abs(warp / want - 1) < 1e-6, qPrintable(QString("%1: warp %2 W against %3 W").arg(lattice_name(mesh)).arg(warp).arg(want)));
            L.setZero();
            L(1, 1) = edot;
            QVERIFY(std::abs(power(L) / want - 1) < 1e-6);
            L.setZero();
            L(0, 1) = -edot;
            L(1, 0) = edot; // a rigid rotation rate
            QVERIFY(std::abs(power(L)) < 1e-12 * want);
        }
    }

    /// A garment panel imported in its 3D shape - a quarter of a cylinder, a
    /// closed tube (a sleeve) - is stress-free in that shape: the membrane's rest
    /// state is the mesh's own, not its projection on a plane (the first version
    /// of the fibre membrane measured the rest shape in the projected material
    /// coordinates and pulled a tube with 800 N).
    void triangle_membrane_rests_in_a_curved_rest_shape_data()
    {
        QTest::addColumn<double>("sweep");
        QTest::newRow("quarter cylinder") << std::numbers::pi / 2;
        QTest::newRow("tube") << 2 * std::numbers::pi;
    }
    void triangle_membrane_rests_in_a_curved_rest_shape()
    {
        QFETCH(double, sweep);
        const bool closed = sweep > 6;
        const int na = 24, nz = 10;
        const double R = 0.06, len = 0.2;
        const int cols = closed ? na : na + 1;
        Positions X(cols * nz, 3);
        for (int j = 0; j < nz; ++j)
            for (int i = 0; i < cols; ++i) {
                const double t = sweep * i / na;
                X.row(i + cols * j) << R * std::cos(t), R * std::sin(t), len * j / (nz - 1);
            }
        std::vector<Eigen::Vector3i> tris;
        for (int j = 0; j + 1 < nz; ++j)
            for (int i = 0; i < na; ++i) {
                const int a = i + cols * j, b = (i + 1) % cols + cols * j, c = a + cols, d = b + cols;
                tris.emplace_back(a, b, d);
                tris.emplace_back(a, d, c);
            }
        Triangles F(static_cast<Eigen::Index>(tris.size()), 3);
        for (std::size_t t = 0; t < tris.size(); ++t) F.row(static_cast<Eigen::Index>(t)) = tris[t].transpose();
        const ClothMesh m = make_triangle_mesh(X, F, Eigen::Vector3d::UnitZ());
        FabricParams p = undamped();
        p[Param::BucklingLength] = 0.0075;
        ClothModel model = make_model(m, p);
        model.gravity.setZero();
        model.bends.clear(); // the membrane alone
        QVERIFY(!model.fibers.empty());
        const ClothSystem s(m, model);
        Positions f;
        s.conservative_forces(m.X, f);
        const double weight = p[Param::AreaDensity] * 9.81 * m.area();
        QVERIFY2(std::abs(s.potential_energy(m.X)) < 1e-12, qPrintable(QString("energy at rest %1 J").arg(s.potential_energy(m.X))));
        QVERIFY2(f.rowwise().norm().maxCoeff() < 1e-9 * weight, qPrintable(QString("largest force at rest %1 N").arg(f.rowwise().norm().maxCoeff())));
        // And it still resists: stretched 1 % along the axis (the warp here), the
        // tube stores A Eu eps^2 / 2 (the diagonals' weft coupling held: weft unstretched).
        Positions Y = m.X;
        Y.col(2) *= 1.01;
        const double want = 0.5 * p[Param::StretchWarp] * 1e-4 * m.area();
        QVERIFY2(std::abs(s.potential_energy(Y) / want - 1) < 0.02, qPrintable(QString("%1 J against %2 J").arg(s.potential_energy(Y)).arg(want)));
    }

    /// The drapemeter's ring mesh (DrapeMesh::Rings) is a disc: one connected
    /// sheet (V - E + F = 1), every edge in one or two triangles, all triangles
    /// counter-clockwise and no sliver (angles above 15 degrees; 18-26 measured),
    /// the hem on the cut circle, a vertex on
    /// the axis (the centre's tether), and the spacing refined to 0.4 of the
    /// nominal one in the rim's band.
    void ring_disc_is_a_graded_disc_data()
    {
        QTest::addColumn<int>("grid");
        QTest::addColumn<int>("mesh");
        for (int g : {25, 41, 61})
            for (int m = 0; m < 2; ++m) QTest::newRow(qPrintable(QString("grid %1 %2").arg(g).arg(m ? "graded" : "uniform"))) << g << m;
        QTest::newRow("240/180 graded, grid 41") << 41 << 2;
    }
    void ring_disc_is_a_graded_disc()
    {
        QFETCH(int, grid);
        QFETCH(int, mesh);
        DrapeSetup setup;
        setup.grid = grid;
        setup.mesh = DrapeMesh::Rings;
        if (mesh == 2) {
            setup.sample_diameter = 0.24;
            setup.disc_diameter = 0.18;
        }
        const RingGrading grading = mesh == 0 ? RingGrading{} : drapemeter_rim_grading(setup);
        const ClothMesh m = mesh == 0 ? make_ring_disc(setup.sample_diameter, grid) : make_drape_mesh(setup);
        const double R = setup.sample_diameter / 2, h0 = setup.sample_diameter / (grid - 1);
        QVERIFY(!m.grid.valid());
        QCOMPARE(m.X.row(0).norm(), 0.0);
        std::map<std::pair<int, int>, int> edges;
        double min_angle = 1e9;
        double band_sum = 0, outer_sum = 0;
        int band_n = 0, outer_n = 0;
        for (int t = 0; t < m.F.rows(); ++t) {
            Eigen::Vector2d p[3];
            for (int c = 0; c < 3; ++c) p[c] = m.X.row(m.F(t, c)).head<2>().transpose();
            const Eigen::Vector2d e1 = p[1] - p[0], e2 = p[2] - p[0];
            QVERIFY2(e1.x() * e2.y() - e1.y() * e2.x() > 0, qPrintable(QString("triangle %1 is not counter-clockwise").arg(t)));
            const double r = ((p[0] + p[1] + p[2]) / 3).norm();
            for (int c = 0; c < 3; ++c) {
                const Eigen::Vector2d a = p[(c + 1) % 3] - p[c], b = p[(c + 2) % 3] - p[c];
                min_angle = std::min(min_angle, std::acos(a.dot(b) / (a.norm() * b.norm())) * 180 / std::numbers::pi);
                const int i = m.F(t, c), j = m.F(t, (c + 1) % 3);
                ++edges[{std::min(i, j), std::max(i, j)}];
                if (r > grading.inner_radius && r < grading.outer_radius) band_sum += a.norm(), ++band_n;
                if (r > grading.outer_radius + grading.taper + h0 && r < R - h0) outer_sum += a.norm(), ++outer_n;
            }
        }
        for (const auto& [e, n] : edges) QVERIFY2(n == 1 || n == 2, qPrintable(QString("edge %1-%2 in %3 triangles").arg(e.first).arg(e.second).arg(n)));
        QCOMPARE(m.vertex_count() - static_cast<int>(edges.size()) + static_cast<int>(m.F.rows()), 1);
        qInfo("%d vertices, %d triangles, smallest angle %.1f deg", m.vertex_count(), static_cast<int>(m.F.rows()), min_angle);
        QVERIFY2(min_angle > 15, qPrintable(QString("smallest angle %1 deg").arg(min_angle)));
        double hem_err = 0;
        int hem = 0;
        for (int i = 0; i < m.vertex_count(); ++i)
            if (m.boundary[static_cast<std::size_t>(i)]) hem_err = std::max(hem_err, std::abs(m.X.row(i).norm() - R)), ++hem;
        QVERIFY(hem > 0);
        QVERIFY2(hem_err < 1e-12, qPrintable(QString("a hem vertex is %1 m off the circle").arg(hem_err)));
        const double inscribed = std::numbers::pi * R * R * (1 - std::pow(2 * std::numbers::pi / hem, 2) / 6);
        QVERIFY2(std::abs(m.area() / inscribed - 1) < 1e-3, qPrintable(QString("area %1 m^2, the inscribed polygon's %2").arg(m.area()).arg(inscribed)));
        for (int i = 0; i < m.vertex_count(); ++i) QVERIFY((m.uv.row(i) - Eigen::RowVector2d(m.X(i, 0) + R, m.X(i, 1) + R)).norm() < 1e-15);
        if (mesh > 0) {
            const double band = band_sum / band_n, outer = outer_sum / std::max(1, outer_n);
            qInfo("mean edge in the rim band %.2f mm (nominal %.2f mm x %.1f), outside it %.2f mm", band * 1e3, h0 * 1e3, grading.factor, outer * 1e3);
            QVERIFY2(std::abs(band / (grading.factor * h0) - 1) < 0.2, qPrintable(QString("rim band edges %1 mm").arg(band * 1e3)));
            if (outer_n > 0) QVERIFY2(std::abs(outer / h0 - 1) < 0.2, qPrintable(QString("outer edges %1 mm").arg(outer * 1e3)));
        }
    }

    /// A grading the grid is too coarse for folds the rings over each other: refused
    /// (a 360 mm sheet over a 115 mm disc at grid 5), as are gradings out of range.
    void ring_disc_refuses_what_it_cannot_mesh()
    {
        DrapeSetup s;
        s.sample_diameter = 0.36;
        s.disc_diameter = 0.115;
        QVERIFY_THROWS_EXCEPTION(drape::ParameterError, make_ring_disc(0.36, 5, drapemeter_rim_grading(s)));
        const RingGrading bad[] = {{0.09, 0.065, 0.4, 0.015},          // band inside out
                                   {-0.01, 0.065, 0.4, 0.015},         // negative radius
                                   {0.065, 0.09, 0.01, 0.015},         // too fine: millions of vertices
                                   {0.065, 0.09, 0.4, -0.001},         // negative taper
                                   {0.065, std::nan(""), 0.4, 0.015}}; // not a number
        for (const RingGrading& g : bad) QVERIFY_THROWS_EXCEPTION(drape::ParameterError, make_ring_disc(0.3, 41, g));
    }

    /// The continuation carries a coarse rest state to a finer mesh: between two
    /// ring meshes (whose vertices do not line up) an affine deformation comes
    /// over exactly, inside and at the hem (extrapolated), as between two grids.
    void interpolation_between_meshes_is_exact_for_affine_maps()
    {
        Eigen::Matrix3d A;
        A << 0.9, 0.2, 0.1, -0.3, 1.1, 0.05, 0.4, -0.2, 0.7;
        const Eigen::RowVector3d b(0.01, -0.02, 0.03);
        DrapeSetup s;
        s.mesh = DrapeMesh::Rings;
        for (auto [coarse_grid, fine_grid, fine_mesh] : {std::tuple{41, 81, DrapeMesh::Rings}, std::tuple{25, 61, DrapeMesh::Grid}}) {
            s.grid = coarse_grid;
            const ClothMesh coarse = make_drape_mesh(s);
            DrapeSetup f = s;
            f.grid = fine_grid;
            f.mesh = fine_mesh;
            const ClothMesh fine = make_drape_mesh(f);
            const Positions xc = (coarse.X * A.transpose()).rowwise() + b;
            const Positions xf = interpolate_positions(coarse, xc, fine);
            const Positions expected = (fine.X * A.transpose()).rowwise() + b;
            const double err = (xf - expected).cwiseAbs().maxCoeff();
            QVERIFY2(err < 1e-12, qPrintable(QString("rings %1 -> %2: %3 m off").arg(coarse_grid).arg(fine_grid).arg(err)));
        }
    }

    /// Contact is checked on mesh edges, not only at vertices: a coarse sheet
    /// draped over the pedestal does not cut the corner of its rim (with vertex
    /// contact only, grid 17 cuts it by millimetres, which narrows the laser
    /// slices next to the disc; docs/decisions/0001-edge-contact.md).
    void coarse_sheet_does_not_cut_the_pedestal_rim()
    {
        DrapeSetup setup;
        setup.grid = 17;
        FabricParams p;
        auto deepest_cut = [&](bool edge_contact) {
            ModelOptions mo;
            mo.edge_contact = edge_contact;
            auto sys = make_drape_system(p, setup, mo);
            RestOptions ro;
            const SolverStatus st = run_to_rest(*sys, ro);
            if (!st.converged()) return -1.0;
            const PedestalCollider ped(Eigen::Vector3d::Zero(), setup.disc_diameter / 2, setup.pedestal_height,
                                       std::min(setup.edge_radius, setup.disc_diameter / 4));
            const double off = sys->model().contact_offset;
            double deepest = 0;
            for (const auto& e : sys->edges())
                for (int k = 1; k < 50; ++k) {
                    const double t = k / 50.0;
                    const Eigen::Vector3d q = (1 - t) * sys->x.row(e[0]).transpose() + t * sys->x.row(e[1]).transpose();
                    ContactSample cs;
                    if (ped.query(q, off, cs)) deepest = std::max(deepest, off - cs.distance);
                }
            return deepest;
        };
        const double with_edges = deepest_cut(true), vertices_only = deepest_cut(false);
        qInfo("grid 17: mesh edges cut the rim by %.3f mm with edge contact, %.3f mm with vertex contact only", with_edges * 1e3,
              vertices_only * 1e3);
        QVERIFY2(with_edges >= 0 && vertices_only >= 0, "a drape did not converge");
        QVERIFY2(vertices_only > 1e-3, qPrintable(QString("vertex contact alone cuts %1 mm (the check must see it)").arg(vertices_only * 1e3)));
        QVERIFY2(with_edges < 0.1e-3, qPrintable(QString("edges cut the rim by %1 mm").arg(with_edges * 1e3)));
    }

    /// Limp fabrics wrap the pedestal rim tightly at the fitting grid. Before
    /// the edge contact faded out smoothly, its energy jumped there and the
    /// static solver stalled on a rim vertex for 1000 iterations (D 99.7 %,
    /// i.e. the sheet never fell) at bending 3e-7 N*m; a fit's bisection then
    /// read "too stiff" and went the wrong way.
    void limp_drapes_come_to_rest_on_the_rim()
    {
        DrapeSetup setup;
        setup.grid = 25;
        for (double B : {1e-8, 3e-7, 1e-5}) {
            FabricParams p;
            p[Param::BendWarp] = p[Param::BendWeft] = B;
            p[Param::Shear] = 10;
            p[Param::AreaDensity] = 0.2;
            const DrapeResult r = simulate_drape(p, setup);
            qInfo("bending %.0e N*m: %s after %ld iterations, D %.1f %%", B, r.status.converged() ? "converged" : "NOT converged", r.status.steps,
                  r.metrics.drape_coefficient_percent);
            QVERIFY2(r.status.converged(), qPrintable(QString("bending %1: %2").arg(B).arg(QString::fromStdString(r.status.message))));
            QVERIFY(r.metrics.drape_coefficient_percent < 50);
        }
    }

    void heavy_elastica_limits()
    {
        // Small loads: the linear cantilever, tip drop w L^4 / (8 B), i.e. lambda / 8 of L.
        const ElasticaTip small = heavy_elastica(0.01);
        QVERIFY(small.converged);
        QVERIFY2(std::abs(small.drop / (0.01 / 8) - 1) < 1e-3, qPrintable(QString::number(small.drop)));
        QVERIFY(std::abs(small.reach - 1) < 1e-5);
        // The cantilever bending test (Peirce 1930; ASTM D1388, BS 3356): a strip of
        // twice its bending length c = (B / w)^(1/3), i.e. lambda = 8, bends until the
        // chord from the clamp to its tip lies 41.5 deg below the horizontal - the
        // standards' angle (Peirce's closed-form approximation c = L (cos(theta / 2) /
        // (8 tan theta))^(1/3) puts it at 42.9 deg).
        const ElasticaTip peirce = heavy_elastica(8);
        QVERIFY(peirce.converged);
        const double chord = std::atan2(peirce.drop, peirce.reach) * 180 / std::numbers::pi;
        qInfo("lambda 8: reach %.4f L, drop %.4f L, chord %.2f deg", peirce.reach, peirce.drop, chord);
        QVERIFY2(std::abs(chord - 41.5) < 0.3, qPrintable(QString::number(chord)));
        // An inextensible strip: its tip stays within its length of the clamp, and
        // a heavier (or longer) strip reaches less far and hangs lower.
        double last_reach = 1.1, last_drop = -1;
        for (double lambda : {1.0, 8.0, 30.0, 130.0, 1000.0}) {
            const ElasticaTip t = heavy_elastica(lambda);
            QVERIFY2(t.converged, qPrintable(QString::number(lambda)));
            QVERIFY(std::hypot(t.reach, t.drop) < 1 + 1e-9);
            QVERIFY(t.reach < last_reach && t.drop > last_drop);
            last_reach = t.reach, last_drop = t.drop;
        }
        // The chain converges: 400 and 1600 segments agree.
        QVERIFY(std::abs(heavy_elastica(30, 400).reach - heavy_elastica(30, 1600).reach) < 2e-4);
        QVERIFY_THROWS_EXCEPTION(drape::ParameterError, heavy_elastica(-1));
        QVERIFY_THROWS_EXCEPTION(drape::ParameterError, free_strip_bending_bound(0.3, 0.15, 0.2, 100));
        QVERIFY_THROWS_EXCEPTION(drape::ParameterError, free_strip_drape_coefficient(0.15, 0.3, 0.2, 1e-5));
        // The bound inverts the strips' D.
        const double B = free_strip_bending_bound(0.24, 0.18, 0.125, 55.4);
        QVERIFY(std::abs(free_strip_drape_coefficient(0.24, 0.18, 0.125, B) - 55.4) < 1e-6);
    }

    void cantilever_droops_as_the_heavy_elastica_data()
    {
        QTest::addColumn<double>("bending");
        QTest::newRow("lambda 2") << 1.6e-5;
        QTest::newRow("lambda 8") << 4e-6;
        QTest::newRow("lambda 30") << 1.1e-6;
    }
    void cantilever_droops_as_the_heavy_elastica()
    {
        // A strip 30 mm long and 10 mm wide, clamped by its first two columns of
        // vertices (position and slope), 125 g/m^2, at rest under gravity: its tip
        // hangs where the heavy elastica's does. The analytic check of the bending
        // that the drapes' free-strip bound rests on.
        QFETCH(double, bending);
        const double L = 0.030, W = 0.010, h = 1.0e-3, rho = 0.125;
        const int nu = static_cast<int>(std::lround(L / h)) + 2, nv = static_cast<int>(std::lround(W / h)) + 1;
        // The clamp's two columns at x = -h and 0; the free length L beyond.
        ClothMesh m = make_rectangle(L + h, W, nu, nv, Eigen::Vector3d(-h, 0, 0));
        FabricParams p;
        p[Param::BendWarp] = p[Param::BendWeft] = bending;
        p[Param::AreaDensity] = rho;
        ClothSystem s(m, make_model(m, p));
        for (int j = 0; j < nv; ++j)
            for (int i = 0; i < 2; ++i) s.set_pinned(m.grid.at(i, j), true);
        RestOptions ro;
        ro.integrator = Integrator::Static;
        const SolverStatus st = run_to_rest(s, ro);
        QVERIFY2(st.converged(), st.message.c_str());
        double reach = 0, drop = 0;
        for (int j = 0; j < nv; ++j) reach += s.x(m.grid.at(nu - 1, j), 0) / nv, drop -= s.x(m.grid.at(nu - 1, j), 2) / nv;
        const ElasticaTip e = heavy_elastica(rho * 9.81 * L * L * L / bending);
        qInfo("lambda %.1f: engine reach %.2f mm, drop %.2f mm; elastica %.2f mm, %.2f mm", rho * 9.81 * L * L * L / bending, reach * 1e3,
              drop * 1e3, e.reach * L * 1e3, e.drop * L * 1e3);
        QVERIFY2(std::abs(reach - e.reach * L) < 0.03 * L && std::abs(drop - e.drop * L) < 0.03 * L,
                 qPrintable(QString("engine %1 / %2 mm, elastica %3 / %4 mm").arg(reach * 1e3).arg(drop * 1e3).arg(e.reach * L * 1e3).arg(e.drop * L * 1e3)));
    }

    void drapes_lie_above_their_free_strips_data()
    {
        QTest::addColumn<double>("sample");
        QTest::addColumn<double>("disc");
        QTest::addColumn<double>("bending");
        QTest::newRow("240/180, B 4e-6") << 0.24 << 0.18 << 4e-6;
        QTest::newRow("240/180, B 1.3e-6") << 0.24 << 0.18 << 1.3e-6;
        QTest::newRow("300/150, B 4e-6") << 0.30 << 0.15 << 4e-6;
    }
    void drapes_lie_above_their_free_strips()
    {
        // The free-strip bound's premise on the engine's own drapes: an annulus of
        // linear bending B drapes at or above the D of its radial strips, each a heavy
        // elastica clamped at the rim (it must fold or shorten around its
        // circumference to fall; they need not).
        QFETCH(double, sample);
        QFETCH(double, disc);
        QFETCH(double, bending);
#if defined(__SANITIZE_ADDRESS__)
        if (QByteArray(QTest::currentDataTag()) != "240/180, B 4e-6") QSKIP("under the sanitizers one drape reaches the same code");
#endif
        DrapeSetup setup;
        setup.sample_diameter = sample;
        setup.disc_diameter = disc;
        setup.grid = 33;
        FabricParams p;
        p[Param::BendWarp] = p[Param::BendWeft] = bending;
        p[Param::AreaDensity] = 0.125;
        p[Param::Shear] = 20;
        const DrapeResult r = simulate_drape(p, setup);
        QVERIFY2(r.status.converged(), r.status.message.c_str());
        const double strips = free_strip_drape_coefficient(sample, disc, 0.125, bending);
        qInfo("drape %.1f %%, its free strips %.1f %%", r.metrics.drape_coefficient_percent, strips);
        QVERIFY(r.metrics.drape_coefficient_percent > strips);
    }

    void run_to_rest_reports_divergence()
    {
        // An explicit step far above the stability limit must end as "diverged", not as garbage.
        FabricParams p;
        DrapeSetup setup;
        setup.grid = 15;
        auto s = make_drape_system(p, setup);
        RestOptions ro;
        ro.integrator = Integrator::ExplicitEuler;
        ro.dt = 1e-2;
        ro.max_sim_time = 5;
        const SolverStatus st = run_to_rest(*s, ro);
        QCOMPARE(st.outcome, SolverStatus::Outcome::Diverged);
        QVERIFY(!st.message.empty());
    }
};

QTEST_APPLESS_MAIN(TestPhysics)
#include "tst_physics.moc"
