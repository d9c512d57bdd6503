// MeshCollider: BVH closest points against brute force, the sign against the
// generalized winding number, exact signed distance of a thin box, normals as
// the gradient of the distance, offset and band.
#include "engine/cloth/colliders.hpp"
#include "engine/cloth/model.hpp"
#include "engine/cloth/system.hpp"
#include "engine/core/error.hpp"
#include "importers/mesh_collider.hpp"
#include "importers/mesh_import.hpp"

#include <Eigen/Geometry>
#include <QTest>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>

using namespace drape;
using namespace drape::importers;
using Vec3 = Eigen::Vector3d;

namespace {

/// Brute-force distance from p to triangle abc by sampling nothing: the exact
/// minimum over the plane projection (if inside) and the three edges.
double point_segment(const Vec3& p, const Vec3& a, const Vec3& b)
{
    const Vec3 ab = b - a;
    const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
    return (p - (a + t * ab)).norm();
}

double point_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c)
{
    const Vec3 n = (b - a).cross(c - a);
    const double nn = n.squaredNorm();
    // Projection onto the plane, then the inside test with signed sub-areas.
    const Vec3 q = p - n * ((p - a).dot(n) / nn);
    const bool inside = (b - a).cross(q - a).dot(n) >= 0 && (c - b).cross(q - b).dot(n) >= 0 &&
                        (a - c).cross(q - c).dot(n) >= 0;
    if (inside) return (p - q).norm();
    return std::min({point_segment(p, a, b), point_segment(p, b, c), point_segment(p, c, a)});
}

double brute_distance(const cloth::Positions& X, const cloth::Triangles& F, const Vec3& p)
{
    double best = std::numeric_limits<double>::infinity();
    for (int t = 0; t < F.rows(); ++t) best = std::min(best, point_triangle(p, X.row(F(t, 0)), X.row(F(t, 1)), X.row(F(t, 2))));
    return best;
}

/// Generalized winding number (Jacobson, Kavan, Sorkine-Hornung 2013), solid
/// angles by Van Oosterom and Strackee 1983: ~1 inside a closed mesh, ~0 outside.
double winding_number(const cloth::Positions& X, const cloth::Triangles& F, const Vec3& p)
{
    double w = 0;
    for (int t = 0; t < F.rows(); ++t) {
        const Vec3 a = X.row(F(t, 0)).transpose() - p, b = X.row(F(t, 1)).transpose() - p,
                   c = X.row(F(t, 2)).transpose() - p;
        const double la = a.norm(), lb = b.norm(), lc = c.norm();
        const double num = a.dot(b.cross(c));
        const double den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
        w += 2.0 * std::atan2(num, den);
    }
    return w / (4.0 * std::numbers::pi);
}

/// Axis-aligned box [-h, h] as 12 outward triangles.
void make_box(const Vec3& h, cloth::Positions& X, cloth::Triangles& F)
{
    X.resize(8, 3);
    for (int i = 0; i < 8; ++i) X.row(i) << ((i & 1) ? h.x() : -h.x()), ((i & 2) ? h.y() : -h.y()), ((i & 4) ? h.z() : -h.z());
    F.resize(12, 3);
    F << 0, 2, 1, 1, 2, 3, // z-
        4, 5, 6, 5, 7, 6,  // z+
        0, 1, 4, 1, 5, 4,  // y-
        2, 6, 3, 3, 6, 7,  // y+
        0, 4, 2, 2, 4, 6,  // x-
        1, 3, 5, 3, 7, 5;  // x+
}

double box_sdf(const Vec3& p, const Vec3& h)
{
    const Vec3 q = p.cwiseAbs() - h;
    return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

const ImportedMesh& human_body()
{
    static const ImportedScene s = import_scene("/usr/share/assimp/models/Collada/human.zae");
    return *s.find("human-baseMesh");
}

} // namespace

class TestMeshCollider : public QObject {
    Q_OBJECT
private slots:
    void closestPointMatchesBruteForceOnTheBody()
    {
        const ImportedMesh& body = human_body();
        const MeshCollider mc(body.X, body.F);
        QCOMPARE(mc.open_or_nonmanifold_edges(), 0); // the MakeHuman body is closed
        const AlignedBox b = body.bounds();
        std::mt19937_64 rng(7);
        std::uniform_real_distribution<double> U(0, 1);
        int near_surface = 0;
        double worst = 0;
        for (int i = 0; i < 250; ++i) {
            // Half the points uniformly in the padded box, half near the surface.
            Vec3 p;
            if (i % 2 == 0) {
                p = b.min - Vec3::Constant(0.1) + (b.size() + Vec3::Constant(0.2)).cwiseProduct(Vec3(U(rng), U(rng), U(rng)));
            } else {
                const int v = static_cast<int>(U(rng) * static_cast<double>(body.X.rows() - 1));
                p = body.X.row(v).transpose() + 0.01 * Vec3(U(rng) - 0.5, U(rng) - 0.5, U(rng) - 0.5);
                ++near_surface;
            }
            ClosestPoint cp;
            QVERIFY(mc.closest_point(p, cp));
            const double ref = brute_distance(body.X, body.F, p);
            worst = std::max(worst, std::abs(cp.distance - ref));
            QVERIFY2(std::abs(cp.distance - ref) <= 1e-12 + 1e-9 * ref,
                     qPrintable(QString("query %1: bvh %2 brute %3").arg(i).arg(cp.distance, 0, 'g', 17).arg(ref, 0, 'g', 17)));
            // The reported point lies on the reported triangle at that distance.
            QVERIFY(std::abs((p - cp.point).norm() - cp.distance) < 1e-12);
        }
        qInfo("250 queries on %d triangles (%d near the surface): worst |bvh - brute| = %.3g m", body.triangle_count(),
              near_surface, worst);
    }

    void signMatchesWindingNumber()
    {
        const ImportedMesh& body = human_body();
        const MeshCollider mc(body.X, body.F);
        const AlignedBox b = body.bounds();
        std::mt19937_64 rng(11);
        std::uniform_real_distribution<double> U(0, 1);
        int inside = 0, checked = 0;
        for (int i = 0; i < 200; ++i) {
            Vec3 p;
            if (i % 3 == 0) {
                p = b.min + b.size().cwiseProduct(Vec3(U(rng), U(rng), U(rng)));
            } else {
                // Close to the surface, including fingers and toes: the hard cases.
                const int v = static_cast<int>(U(rng) * static_cast<double>(body.X.rows() - 1));
                p = body.X.row(v).transpose() + 0.004 * Vec3(U(rng) - 0.5, U(rng) - 0.5, U(rng) - 0.5);
            }
            const double sd = mc.signed_distance(p);
            if (std::abs(sd) < 1e-7) continue; // on the surface the sign is a coin toss for both
            const double w = winding_number(body.X, body.F, p);
            QVERIFY2(std::abs(w) < 0.05 || std::abs(w - 1) < 0.05, qPrintable(QString("winding %1").arg(w)));
            const bool in_w = w > 0.5;
            QVERIFY2(in_w == (sd < 0), qPrintable(QString("query %1: sd %2, winding %3").arg(i).arg(sd).arg(w)));
            inside += in_w;
            ++checked;
        }
        qInfo("%d of %d checked points inside the body, all signs agree with the winding number", inside, checked);
        QVERIFY(inside > 20 && inside < checked - 20); // both sides were exercised
    }

    void thinBoxIsExact()
    {
        // A 2 mm plate (a table edge, a finger): signed distance must equal the
        // analytic box SDF, including inside the plate and around its edges.
        const Vec3 h(0.1, 0.08, 0.001);
        cloth::Positions X;
        cloth::Triangles F;
        make_box(h, X, F);
        const MeshCollider mc(X, F);
        QCOMPARE(mc.open_or_nonmanifold_edges(), 0);
        std::mt19937_64 rng(3);
        std::uniform_real_distribution<double> U(-1, 1);
        int inside = 0;
        for (int i = 0; i < 2000; ++i) {
            const Vec3 p(0.12 * U(rng), 0.1 * U(rng), (i % 2 ? 0.0012 : 0.01) * U(rng));
            const double ref = box_sdf(p, h);
            const double sd = mc.signed_distance(p);
            QVERIFY2(std::abs(sd - ref) < 1e-12, qPrintable(QString("p %1 %2 %3: sd %4 ref %5").arg(p.x()).arg(p.y()).arg(p.z()).arg(sd).arg(ref)));
            inside += ref < 0;
        }
        QVERIFY(inside > 100);
    }

    void normalIsTheDistanceGradient()
    {
        const Vec3 h(0.1, 0.08, 0.001);
        cloth::Positions X;
        cloth::Triangles F;
        make_box(h, X, F);
        const MeshCollider mc(X, F);
        std::mt19937_64 rng(5);
        std::uniform_real_distribution<double> U(-1, 1);
        const double eps = 1e-7;
        int tested = 0;
        for (int i = 0; i < 500; ++i) {
            const Vec3 p(0.13 * U(rng), 0.11 * U(rng), 0.02 * U(rng));
            // Skip points inside (the medial surface of the box makes the
            // gradient jump within eps of it) and right on the surface.
            if (box_sdf(p, h) < 1e-4) continue;
            cloth::ContactSample s;
            QVERIFY(mc.query(p, 1.0, s));
            Vec3 g;
            for (int k = 0; k < 3; ++k) {
                Vec3 dp = Vec3::Zero();
                dp[k] = eps;
                g[k] = (mc.signed_distance(p + dp) - mc.signed_distance(p - dp)) / (2 * eps);
            }
            QVERIFY2((g - s.normal).norm() < 1e-5, qPrintable(QString("gradient error %1").arg((g - s.normal).norm())));
            QVERIFY(std::abs(s.normal.norm() - 1) < 1e-12);
            ++tested;
        }
        QVERIFY(tested > 200);
    }

    void offsetAndBand()
    {
        const Vec3 h(0.1, 0.1, 0.1);
        cloth::Positions X;
        cloth::Triangles F;
        make_box(h, X, F);
        const double offset = 0.005;
        const MeshCollider mc(X, F, offset);
        cloth::ContactSample s;
        // 3 mm above the top face is 2 mm inside the offset surface.
        QVERIFY(mc.query(Vec3(0.01, 0.02, 0.103), 0.01, s));
        QVERIFY(std::abs(s.distance - (0.003 - offset)) < 1e-12);
        QVERIFY((s.normal - Vec3::UnitZ()).norm() < 1e-12);
        // Inside the box: negative, normal still outward (towards the nearest face +x).
        QVERIFY(mc.query(Vec3(0.09, 0.0, 0.0), 0.05, s));
        QVERIFY(std::abs(s.distance - (-0.01 - offset)) < 1e-12);
        QVERIFY((s.normal - Vec3::UnitX()).norm() < 1e-12);
        // Deep inside, far beyond the band: still answered, so penetration is never missed.
        QVERIFY(mc.query(Vec3(0.0, 0.0, 0.0), 0.001, s));
        QVERIFY(std::abs(s.distance - (-0.1 - offset)) < 1e-12);
        // Outside and farther than band + offset: not reported.
        QVERIFY(!mc.query(Vec3(0, 0, 0.5), 0.05, s));
        QVERIFY(mc.query(Vec3(0, 0, 0.5), 0.5, s));
        QVERIFY(std::abs(s.distance - (0.4 - offset)) < 1e-12);
        // Works through the Collider interface, e.g. inside a group with the floor.
        cloth::ColliderGroup group;
        group.add(std::make_shared<MeshCollider>(X, F, offset));
        QVERIFY(group.query(Vec3(0.01, 0.02, 0.103), 0.01, s));
        QVERIFY(std::abs(s.distance - (0.003 - offset)) < 1e-12);
        QCOMPARE(mc.kind(), std::string("mesh"));
    }

    /// A point outside reports how far it may move and stay out of reach, and
    /// that is true: within the clearance the query keeps returning false.
    void clearanceIsSafe()
    {
        cloth::Positions X;
        cloth::Triangles F;
        make_box(Vec3(0.1, 0.1, 0.1), X, F);
        const MeshCollider mc(X, F, 0.005);
        std::mt19937 rng(7);
        std::uniform_real_distribution<double> U(-1, 1);
        int checked = 0;
        for (int n = 0; n < 2000; ++n) {
            const Vec3 p(0.4 * U(rng), 0.4 * U(rng), 0.4 * U(rng));
            cloth::ContactSample s;
            if (mc.query(p, 0.01, s)) continue;
            QVERIFY(s.clearance > 0);
            for (int k = 0; k < 5; ++k) {
                const Vec3 q = p + 0.999 * s.clearance * Vec3(U(rng), U(rng), U(rng)).normalized();
                cloth::ContactSample t;
                QVERIFY2(!mc.query(q, 0.01, t), qPrintable(QString("moved %1 of clearance %2").arg((q - p).norm()).arg(s.clearance)));
                ++checked;
            }
        }
        QVERIFY(checked > 1000);
    }

    /// The engine skips queries within the clearance: a cloth walking in and out
    /// of contact gets bit for bit the energy and forces of a fresh system (one
    /// that has never seen the earlier positions).
    void skippedQueriesChangeNothing()
    {
        cloth::Positions X;
        cloth::Triangles F;
        make_box(Vec3(0.1, 0.1, 0.1), X, F);
        cloth::ClothMesh mesh = cloth::make_rectangle(0.3, 0.3, 12, 12, Eigen::Vector3d(-0.15, -0.15, 0));
        cloth::FabricParams p;
        cloth::ClothSystem sys(mesh, cloth::make_model(mesh, p));
        sys.add_collider(std::make_shared<MeshCollider>(X, F, 0.002));
        std::mt19937 rng(11);
        std::uniform_real_distribution<double> U(-1, 1);
        cloth::Positions x = sys.x;
        x.col(2).array() += 0.13;
        int in_contact = 0;
        for (int step = 0; step < 60; ++step) {
            // Steps from 0.1 mm to 3 cm, drifting down through the box's top.
            const double h = std::pow(10.0, -4 + 2.5 * (U(rng) + 1) / 2);
            for (int i = 0; i < x.rows(); ++i) x.row(i) += h * Eigen::RowVector3d(U(rng), U(rng), U(rng) - 0.3);
            cloth::ClothSystem fresh = sys;
            cloth::Positions f1, f2;
            sys.conservative_forces(x, f1);
            fresh.conservative_forces(x, f2);
            QCOMPARE(sys.potential_energy(x), fresh.potential_energy(x));
            QVERIFY((f1 - f2).cwiseAbs().maxCoeff() == 0.0);
            in_contact += sys.vertex_contact_count(x) > 0;
        }
        QVERIFY2(in_contact > 5 && in_contact < 60, qPrintable(QString("%1 of 60 states in contact").arg(in_contact)));
    }

    void openMeshIsOneSided()
    {
        // A table top without an underside: the side of the nearest piece.
        cloth::Positions X(4, 3);
        X << -1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0;
        cloth::Triangles F(2, 3);
        F << 0, 1, 2, 0, 2, 3;
        const MeshCollider mc(X, F);
        QVERIFY(mc.open_or_nonmanifold_edges() == 4);
        QVERIFY(std::abs(mc.signed_distance(Vec3(0.2, 0.3, 0.05)) - 0.05) < 1e-12);
        QVERIFY(std::abs(mc.signed_distance(Vec3(0.2, 0.3, -0.05)) + 0.05) < 1e-12);
    }

    void rejectsBadInput()
    {
        cloth::Positions X(3, 3);
        X << 0, 0, 0, 1, 0, 0, 0, 1, 0;
        cloth::Triangles F(1, 3);
        F << 0, 1, 3;
        QVERIFY_THROWS_EXCEPTION(ParameterError, MeshCollider(X, F));
        F << 0, 1, 2;
        QVERIFY_THROWS_EXCEPTION(ParameterError, MeshCollider(X, F, -1e-3));
        QVERIFY_THROWS_EXCEPTION(ParameterError, MeshCollider(X, cloth::Triangles(0, 3)));
        X(1, 1) = std::numeric_limits<double>::quiet_NaN();
        QVERIFY_THROWS_EXCEPTION(ParameterError, MeshCollider(X, F));
    }
};

QTEST_APPLESS_MAIN(TestMeshCollider)
#include "tst_mesh_collider.moc"
