// Finite-difference checks of every force (against the energy) and of the
// exact Hessian (against the forces).
#include "engine/cloth/drape.hpp"
#include "engine/cloth/system.hpp"

#include <Eigen/Eigenvalues>
#include <QtTest>

#include <random>

using namespace drape::cloth;

namespace {

/// A small draped-looking state: the sheet bent over the pedestal edge so that
/// springs are stretched and compressed, stencils bent and contacts active.
std::unique_ptr<ClothSystem> bent_disc(bool triangle_mesh, unsigned seed, double stiffening_radius = 0.0, double softening_radius = 0.0)
{
    FabricParams p;
    p[Param::BendStiffeningRadius] = stiffening_radius;
    p[Param::BendSofteningRadius] = softening_radius;
    p[Param::Shear] = 35.0;
    p[Param::BendWarp] = 2e-5;
    p[Param::BendWeft] = 0.7e-5;
    ClothMesh mesh = make_disc(0.3, 11, 0.0);
    if (triangle_mesh) mesh = make_triangle_mesh(mesh.X, mesh.F, Eigen::Vector3d(1, 0.3, 0));
    auto s = std::make_unique<ClothSystem>(mesh, make_model(mesh, p));
    s->add_collider(std::make_shared<PedestalCollider>(Eigen::Vector3d::Zero(), 0.075, 0.12, 0.004));
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
        QTest::newRow("grid") << false << 0.0 << 0.0;
        QTest::newRow("triangle mesh") << true << 0.0 << 0.0;
        // 20 mm: the nonlinear terms dominate in the sharp bends of this state.
        QTest::newRow("grid, stiffening bending") << false << 0.02 << 0.0;
        QTest::newRow("triangle mesh, stiffening bending") << true << 0.02 << 0.0;
        QTest::newRow("grid, softening bending") << false << 0.0 << 0.02;
        QTest::newRow("triangle mesh, both") << true << 0.01 << 0.02;
    }
    void forces_are_minus_energy_gradient()
    {
        QFETCH(bool, triangles);
        QFETCH(double, stiffening);
        QFETCH(double, softening);
        auto s = bent_disc(triangles, 3, stiffening, softening);
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
        auto s = bent_disc(triangles, 5, stiffening, softening);
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

    void projected_hessian_is_positive_semidefinite_data()
    {
        QTest::addColumn<double>("stiffening");
        QTest::addColumn<double>("softening");
        QTest::newRow("linear bending") << 0.0 << 0.0;
        QTest::newRow("stiffening bending") << 0.02 << 0.0;
        QTest::newRow("softening bending") << 0.0 << 0.02;
    }
    void projected_hessian_is_positive_semidefinite()
    {
        QFETCH(double, stiffening);
        QFETCH(double, softening);
        auto s = bent_disc(false, 7, stiffening, softening);
        HessianAssembler H(*s);
        H.assemble(s->x, Eigen::VectorXd(), 0.0, /*project=*/true);
        const Eigen::MatrixXd Hd = Eigen::MatrixXd(Eigen::MatrixXd(H.matrix()).selfadjointView<Eigen::Upper>());
        Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(Hd);
        QVERIFY(es.eigenvalues().minCoeff() > -1e-8 * es.eigenvalues().maxCoeff());
    }

    void damping_forces_match_damping_matrix()
    {
        // The implicit integrator uses D (dashpots + air) from the assembler; the
        // explicit ones use the damping forces. They must agree: f = -D v.
        auto s = bent_disc(false, 9);
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
