// Exact self-intersection count: pairs of triangles built to intersect (or
// not), with the expected count worked out by hand from the geometry.
#include "engine/cloth/self_intersection.hpp"
#include "engine/core/error.hpp"

#include <QTest>

using namespace drape::cloth;
using V = Eigen::Vector3d;

namespace {
/// An N x N grid of unit cells in z = 0, each cell split along (i, j)-(i+1, j+1).
void add_grid(std::vector<V>& X, std::vector<Eigen::Vector3i>& F, int N)
{
    const int base = static_cast<int>(X.size());
    for (int j = 0; j <= N; ++j)
        for (int i = 0; i <= N; ++i) X.emplace_back(i, j, 0);
    auto id = [&](int i, int j) { return base + i + (N + 1) * j; };
    for (int j = 0; j < N; ++j)
        for (int i = 0; i < N; ++i) {
            F.emplace_back(id(i, j), id(i + 1, j), id(i + 1, j + 1));
            F.emplace_back(id(i, j), id(i + 1, j + 1), id(i, j + 1));
        }
}
void to_mesh(const std::vector<V>& X, const std::vector<Eigen::Vector3i>& F, Positions& P, Triangles& T)
{
    P.resize(static_cast<Eigen::Index>(X.size()), 3);
    T.resize(static_cast<Eigen::Index>(F.size()), 3);
    for (std::size_t i = 0; i < X.size(); ++i) P.row(static_cast<Eigen::Index>(i)) = X[i].transpose();
    for (std::size_t i = 0; i < F.size(); ++i) T.row(static_cast<Eigen::Index>(i)) = F[i].transpose();
}
} // namespace

class TestSelfIntersection : public QObject {
    Q_OBJECT
private slots:
    void pairs_of_triangles()
    {
        const V a0(0, 0, 0), a1(1, 0, 0), a2(0, 1, 0);
        // Crossing: a vertical triangle through the middle of a.
        QVERIFY(triangles_intersect(a0, a1, a2, V(0.2, 0.2, -1), V(0.2, 0.2, 1), V(0.3, 0.1, 0.5)));
        // Above, apart.
        QVERIFY(!triangles_intersect(a0, a1, a2, V(0, 0, 1e-6), V(1, 0, 1e-6), V(0, 1, 1e-6)));
        // One vertex exactly on the other's face: touching counts.
        QVERIFY(triangles_intersect(a0, a1, a2, V(0.25, 0.25, 0), V(0.25, 0.25, 1), V(0.5, 0.5, 1)));
        // A hair's breadth (2 nm) above the face: apart.
        QVERIFY(!triangles_intersect(a0, a1, a2, V(0.25, 0.25, 2e-9), V(0.25, 0.25, 1), V(0.5, 0.5, 1)));
        // Coplanar and overlapping.
        QVERIFY(triangles_intersect(a0, a1, a2, V(0.1, 0.1, 0), V(2, 0.1, 0), V(0.1, 2, 0)));
        // Coplanar, disjoint.
        QVERIFY(!triangles_intersect(a0, a1, a2, V(2, 2, 0), V(3, 2, 0), V(2, 3, 0)));
        // An edge passing through the other triangle's edge (in its plane's line).
        QVERIFY(triangles_intersect(a0, a1, a2, V(0.5, -1, 0), V(0.5, 1, 0.0), V(0.5, 0, 1)));
    }

    void flat_and_parallel_sheets_do_not_intersect()
    {
        std::vector<V> X;
        std::vector<Eigen::Vector3i> F;
        add_grid(X, F, 6);
        Positions P;
        Triangles T;
        to_mesh(X, F, P, T);
        QCOMPARE(self_intersections(P, T).pairs, 0L);
        // A second sheet 1 mm above the first: still none.
        const int n = static_cast<int>(X.size());
        add_grid(X, F, 6);
        for (std::size_t i = static_cast<std::size_t>(n); i < X.size(); ++i) X[i].z() = 1e-3;
        to_mesh(X, F, P, T);
        QCOMPARE(self_intersections(P, T).pairs, 0L);
    }

    void a_sheet_through_a_sheet_gives_the_counted_pairs()
    {
        // A 5 x 5 sheet in z = 0 and a rectangle in the plane x = 1.3 spanning
        // y -1..6, z -1..1, split along the diagonal (-1, -1)-(6, 1), which
        // crosses z = 0 at y = 2.5. The sheet's triangles met by the line
        // x = 1.3: per row j the lower one covers y in [j, j + 0.3], the upper one
        // [j + 0.3, j + 1]. The rectangle's triangle on the y > 2.5 side meets
        // lower j = 3, 4 and upper j = 2, 3, 4 (5 pairs), the other one lower
        // j = 0, 1, 2 and upper j = 0, 1, 2 (6 pairs): 11 in all.
        std::vector<V> X;
        std::vector<Eigen::Vector3i> F;
        add_grid(X, F, 5);
        const int b = static_cast<int>(X.size());
        X.emplace_back(1.3, -1, -1);
        X.emplace_back(1.3, 6, -1);
        X.emplace_back(1.3, 6, 1);
        X.emplace_back(1.3, -1, 1);
        F.emplace_back(b, b + 1, b + 2);
        F.emplace_back(b, b + 2, b + 3);
        Positions P;
        Triangles T;
        to_mesh(X, F, P, T);
        QCOMPARE(self_intersections(P, T).pairs, 11L);
        // Lift the rectangle clear of the sheet: none.
        for (int k = 0; k < 4; ++k) P(b + k, 2) += 1.5;
        QCOMPARE(self_intersections(P, T).pairs, 0L);
    }

    void neighbours_sharing_a_vertex_are_not_counted()
    {
        // A fan of triangles around one vertex folded onto itself: every pair
        // shares the centre, so nothing counts even where faces overlap.
        Positions P(4, 3);
        P << 0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 0.1, 0;
        Triangles T(2, 3);
        T << 0, 1, 2, 0, 3, 2;
        QCOMPARE(self_intersections(P, T).pairs, 0L);
    }

    void bad_input_is_refused()
    {
        Positions P(3, 3);
        P << 0, 0, 0, 1, 0, 0, 0, std::nan(""), 0;
        Triangles T(1, 3);
        T << 0, 1, 2;
        QVERIFY_THROWS_EXCEPTION(drape::ParameterError, self_intersections(P, T));
        P(2, 1) = 1;
        T << 0, 1, 7;
        QVERIFY_THROWS_EXCEPTION(drape::ParameterError, self_intersections(P, T));
    }
};

QTEST_APPLESS_MAIN(TestSelfIntersection)
#include "tst_self_intersection.moc"
