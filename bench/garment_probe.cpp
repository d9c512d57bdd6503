// Headless fitting without a window: prints the mannequin's bounding box, the
// measured waist, drapes the garment with the demo's solver options and prints
// the solver status and how close the cloth comes to the body. For measuring
// and debugging the demo's scene (not a test: it prints wall-clock numbers).
//
//   garment_probe [skirt|tablecloth] [FABRIC_PRESET] [OUT.obj]
#include "importers/garment_scene.hpp"

#include <chrono>
#include <cstdio>
#include <fstream>

using namespace drape;

int main(int argc, char** argv)
{
    try {
        const std::string garment = argc > 1 ? argv[1] : "skirt";
        const std::string fabric = argc > 2 ? argv[2] : "seed-table1";
        const fabric::FabricPreset preset = fabric::load_fabric(fabric);
        auto m = std::make_shared<importers::Mannequin>(importers::load_mannequin(importers::default_mannequin_path()));
        const auto& b = m->bounds;
        std::printf("mannequin %d vertices, %d triangles, bbox min (%.3f %.3f %.3f) max (%.3f %.3f %.3f) m, height %.3f m, open edges %d\n",
                    m->mesh.vertex_count(), m->mesh.triangle_count(), b.min.x(), b.min.y(), b.min.z(), b.max.x(),
                    b.max.y(), b.max.z(), m->height(), m->collider->open_or_nonmanifold_edges());
        for (double f : {0.45, 0.5, 0.53, 0.56, 0.6, 0.62, 0.64, 0.66, 0.7}) {
            const importers::Girth g = importers::measure_girth(*m, f * m->height());
            std::printf("  girth at %.2f H (z %.3f): centre (%.3f %.3f) mean r %.3f max r %.3f hit %d/%d\n", f, g.z,
                        g.centre.x(), g.centre.y(), g.mean_radius, g.max_radius, g.rays_hit, g.rays);
        }
        importers::Scene s = garment == "skirt" ? importers::make_skirt_scene(m, preset) : importers::make_tablecloth_scene(preset);
        if (garment == "skirt")
            std::printf("waist z %.3f m, mean r %.3f, max r %.3f\n", s.waist.z, s.waist.mean_radius, s.waist.max_radius);
        std::printf("cloth %d vertices, %d triangles\n", s.system->vertex_count(), int(s.system->mesh().F.rows()));
        if (garment == "skirt") {
            const importers::Penetration p0 = importers::body_penetration(*m, s.system->x);
            std::printf("start: min distance %.4f m, inside %d\n", p0.min_distance, p0.inside);
        }
        cloth::RestOptions o = importers::garment_rest_options();
        long last = -50;
        o.progress = [&](const cloth::SolverStatus& st) {
            if (st.newton_iterations - last >= 25) {
                last = st.newton_iterations;
                std::printf("  newton %ld residual %.3g  %.1f s\n", st.newton_iterations, st.residual, st.wall_seconds);
                std::fflush(stdout);
            }
            return true;
        };
        const cloth::SolverStatus st = cloth::run_to_rest(*s.system, o);
        std::printf("%s: %ld Newton iterations, residual %.3g, %.1f s; %s\n", cloth::to_string(st.outcome).c_str(),
                    st.newton_iterations, st.residual, st.wall_seconds, st.message.c_str());
        std::printf("cloth z range %.3f .. %.3f m\n", s.system->x.col(2).minCoeff(), s.system->x.col(2).maxCoeff());
        if (garment == "skirt") {
            const importers::Penetration p = importers::body_penetration(*m, s.system->x);
            std::printf("rest: min distance to the body %.5f m (vertex %d), vertices inside %d\n", p.min_distance,
                        p.worst_vertex, p.inside);
        }
        if (argc > 3) {
            std::ofstream obj(argv[3]);
            for (Eigen::Index i = 0; i < s.system->x.rows(); ++i)
                obj << "v " << s.system->x(i, 0) << ' ' << s.system->x(i, 1) << ' ' << s.system->x(i, 2) << '\n';
            const auto& F = s.system->mesh().F;
            for (Eigen::Index t = 0; t < F.rows(); ++t)
                obj << "f " << F(t, 0) + 1 << ' ' << F(t, 1) + 1 << ' ' << F(t, 2) + 1 << '\n';
        }
        return st.outcome == cloth::SolverStatus::Outcome::Diverged ? 1 : 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "garment_probe: %s\n", e.what());
        return 1;
    }
}
