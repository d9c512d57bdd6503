// Probe: which term a coarse grid gets wrong. A preset's rest state on a fine grid is
// sampled onto a coarse grid (cloth::interpolate_positions) and each term's energy of
// the coarse model there is set beside the fine model's at its rest state: a consistent
// discretisation stores the same energy per term for the same shape (gravity's must
// agree; it checks the sampling). Then the coarse grid's own rest state, for the
// shape the coarse model prefers.
//   consistency PRESET FINE COARSE ARC(0/1) [SEED]
#include "engine/cloth/drape.hpp"
#include "engine/cloth/mesh.hpp"
#include "engine/cloth/solver.hpp"
#include "engine/fabric/preset.hpp"
#include <cstdio>
#include <cstdlib>
using namespace drape;

constexpr int kBands = 6;
constexpr double kBandEdge[kBands] = {0.060, 0.075, 0.090, 0.110, 0.130, 0.151}; // material radius [m]

static int band(double r)
{
    for (int b = 0; b < kBands; ++b)
        if (r < kBandEdge[b]) return b;
    return kBands - 1;
}

struct Terms {
    double stretch = 0, shear = 0, bend = 0, gravity = 0, rest = 0, total = 0;
    double membrane_band[kBands] = {}, bend_band[kBands] = {};
    int compressed = 0, springs = 0;
};

static Terms terms(cloth::ClothSystem& s, const cloth::Positions& x)
{
    Terms t;
    cloth::ClothModel full = s.model();
    const Eigen::RowVector2d centre = s.mesh().uv.colwise().mean();
    t.total = s.potential_energy(x);
    for (int i = 0; i < x.rows(); ++i) t.gravity -= full.mass(i) * full.gravity.dot(x.row(i).transpose());
    for (const auto& sp : full.springs) {
        const double l = full.spring_length(sp, x);
        double e, de, d2e;
        sp.law(l, e, de, d2e);
        (sp.kind == cloth::SpringKind::Shear ? t.shear : t.stretch) += e;
        t.membrane_band[band((0.5 * (s.mesh().uv.row(sp.i) + s.mesh().uv.row(sp.j)) - centre).norm())] += e;
        ++t.springs;
        if (sp.fc > 0 && sp.k * (l - sp.rest) < -0.5 * sp.fc) ++t.compressed;
    }
    s.model().springs.clear();
    s.model().arcs.clear();
    const double no_springs = s.potential_energy(x);
    s.model().bends.clear();
    const double no_bends = s.potential_energy(x);
    for (int b = 0; b < kBands; ++b) {
        s.model().bends.clear();
        for (const auto& st : full.bends) {
            Eigen::RowVector2d c = Eigen::RowVector2d::Zero();
            for (int a = 0; a < st.n; ++a) c += s.mesh().uv.row(st.v[a]);
            if (band((c / st.n - centre).norm()) == b) s.model().bends.push_back(st);
        }
        t.bend_band[b] = s.potential_energy(x) - no_bends;
    }
    s.model() = full;
    t.bend = no_springs - no_bends;
    t.rest = no_bends - t.gravity; // contact, anchors
    return t;
}

static void print(const char* what, const Terms& t, double mJ = 1e3)
{
    std::printf("%-28s stretch %8.3f shear %8.3f bend %8.3f gravity %9.3f contact+anchor %7.3f total %9.3f mJ; %d of %d springs past the limit's onset\n", what,
                mJ * t.stretch, mJ * t.shear, mJ * t.bend, mJ * t.gravity, mJ * t.rest, mJ * t.total, t.compressed, t.springs);
    std::printf("%-28s", "  bend by band [mJ]");
    for (int b = 0; b < kBands; ++b) std::printf(" <%3.0f mm %7.3f", 1e3 * kBandEdge[b], mJ * t.bend_band[b]);
    std::printf("\n%-28s", "  membrane by band [mJ]");
    for (int b = 0; b < kBands; ++b) std::printf(" <%3.0f mm %7.3f", 1e3 * kBandEdge[b], mJ * t.membrane_band[b]);
    std::printf("\n");
}

int main(int argc, char** argv)
{
    if (argc < 5) {
        std::fprintf(stderr, "usage: consistency PRESET FINE COARSE ARC [SEED]\n");
        return 2;
    }
    const auto preset = fabric::load_fabric(argv[1]);
    cloth::ModelOptions mo = preset.model;
    mo.arc_membrane = std::atoi(argv[4]) != 0;
    const auto mat = preset.material();
    cloth::DrapeSetup sf;
    sf.sample_diameter = 0.3;
    sf.disc_diameter = 0.15;
    sf.grid = std::atoi(argv[2]);
    if (argc > 5) sf.seed = std::atoi(argv[5]);
    cloth::DrapeSetup sc = sf;
    sc.grid = std::atoi(argv[3]);
    cloth::RestOptions ro;
    const cloth::DrapeResult rf = cloth::simulate_drape(mat, sf, ro, mo);
    const cloth::DrapeResult rc = cloth::simulate_drape(mat, sc, ro, mo);
    auto fine = cloth::make_drape_system(mat, sf, mo);
    auto coarse = cloth::make_drape_system(mat, sc, mo);
    const cloth::Positions injected = cloth::interpolate_positions(fine->mesh(), rf.x, coarse->mesh());
    std::printf("D: fine %.2f (%d folds), coarse %.2f (%d folds)\n", rf.metrics.drape_coefficient_percent, rf.metrics.node_count,
                rc.metrics.drape_coefficient_percent, rc.metrics.node_count);
    print("fine at its rest", terms(*fine, rf.x));
    print("coarse at the fine rest", terms(*coarse, injected));
    print("coarse at its own rest", terms(*coarse, rc.x));
    return 0;
}
