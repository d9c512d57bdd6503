#include "widget/drape_setup.hpp"

#include "engine/cloth/colliders.hpp"
#include "engine/cloth/model.hpp"
#include "engine/core/error.hpp"
#include "importers/garment_scene.hpp"
#include "importers/mesh_import.hpp"

#include <algorithm>
#include <map>
#include <set>

namespace drape::widget {

namespace {

/// Square sheet of side sample_diameter centred over the pedestal (a seed
/// preset keeps the grid its constants describe), placed like the disc.
std::unique_ptr<cloth::ClothSystem> makeSquareSystem(const fabric::FabricPreset& preset, const cloth::DrapeSetup& setup)
{
    setup.validate();
    const cloth::Material material = preset.material();
    cloth::ClothMesh mesh;
    cloth::ClothModel model;
    if (!material.grid_springs) {
        const double w = setup.sample_diameter;
        mesh = cloth::make_rectangle(w, w, setup.grid, setup.grid, Eigen::Vector3d(-w / 2, -w / 2, 0));
        model = cloth::make_model(mesh, material.params, preset.model);
    } else {
        const cloth::GridSprings& g = *material.grid_springs;
        mesh = cloth::make_rectangle(g.width, g.height, g.cells_u, g.cells_v, Eigen::Vector3d(-g.width / 2, -g.height / 2, 0));
        model = cloth::make_grid_spring_model(mesh, g, preset.model);
    }
    auto sys = std::make_unique<cloth::ClothSystem>(std::move(mesh), std::move(model));
    cloth::place_on_drapemeter(*sys, setup);
    return sys;
}

/// A host's garment mesh as cloth with its pins, on the body (if any) and the floor.
std::unique_ptr<cloth::ClothSystem> makeGarmentSystem(const fabric::FabricPreset& preset, const GarmentMesh& g,
                                                      const std::shared_ptr<const importers::Mannequin>& body)
{
    // A seed preset's continuum equivalent drapes any mesh (as in importers::make_skirt_scene).
    cloth::ClothMesh mesh = cloth::make_triangle_mesh(g.X, g.F, g.warp);
    cloth::ClothModel model = cloth::make_model(mesh, preset.params, preset.model);
    auto sys = std::make_unique<cloth::ClothSystem>(std::move(mesh), std::move(model));
    for (int v : g.pinned) {
        if (v < 0 || v >= sys->vertex_count())
            throw ParameterError("garment: pinned vertex " + std::to_string(v) + " is not in [0, " +
                                 std::to_string(sys->vertex_count()) + ")");
        sys->set_pinned(v, true);
    }
    double floor = 0;
    if (body) {
        sys->add_collider(body->contact);
        floor = body->bounds.min.z();
    } else {
        floor = std::min(0.0, g.X.col(2).minCoeff() - 0.5); // somewhere below a garment hanging free
    }
    sys->add_collider(std::make_shared<cloth::PlaneCollider>(Eigen::Vector3d(0, 0, floor), Eigen::Vector3d::UnitZ()));
    return sys;
}

} // namespace

GarmentMesh loadGarmentMesh(const std::string& path)
{
    const importers::ImportedMesh m = importers::import_scene(path).merged();
    GarmentMesh g;
    g.X = m.X;
    g.F = m.F;
    importers::weld_vertices(g.X, g.F);
    // The top boundary: boundary vertices (on an edge of one triangle) within 1 cm of the highest one.
    std::map<std::pair<int, int>, int> edges;
    for (int t = 0; t < g.F.rows(); ++t)
        for (int k = 0; k < 3; ++k) {
            int a = g.F(t, k), b = g.F(t, (k + 1) % 3);
            if (a > b) std::swap(a, b);
            ++edges[{a, b}];
        }
    std::set<int> boundary;
    for (const auto& [e, n] : edges)
        if (n == 1) {
            boundary.insert(e.first);
            boundary.insert(e.second);
        }
    if (boundary.empty()) throw ParameterError(path + ": the garment mesh is closed; pin its vertices with setGarmentMesh");
    double top = -1e300;
    for (int v : boundary) top = std::max(top, g.X(v, 2));
    for (int v : boundary)
        if (g.X(v, 2) > top - 0.01) g.pinned.push_back(v);
    return g;
}

std::unique_ptr<cloth::ClothSystem> makeDrapeSystem(const DrapeSpec& spec,
                                                    const std::shared_ptr<const importers::Mannequin>& body)
{
    std::unique_ptr<cloth::ClothSystem> sys;
    switch (spec.shape) {
    case Drape::Square: sys = makeSquareSystem(spec.preset, spec.setup); break;
    case Drape::Disc: sys = cloth::make_drape_system(spec.preset.material(), spec.setup, spec.preset.model); break;
    case Drape::Skirt:
        if (!body) throw ParameterError("skirt: no body to put it on");
        sys = importers::make_skirt_scene(body, spec.preset).system;
        break;
    case Drape::Tablecloth: sys = importers::make_tablecloth_scene(spec.preset).system; break;
    case Drape::GarmentMesh:
        if (!spec.garment) throw ParameterError("garment: no garment mesh (setGarmentMesh or garmentFile)");
        sys = makeGarmentSystem(spec.preset, *spec.garment, body);
        break;
    }
    if (!sys || sys->vertex_count() == 0) throw ParameterError("cloth: the mesh has no vertices");
    if (sys->v.rows() != sys->vertex_count()) sys->v.setZero(sys->vertex_count(), 3);
    return sys;
}

double maxFreeSpeed(const cloth::ClothSystem& s)
{
    double m = 0;
    for (int i = 0; i < s.vertex_count(); ++i)
        if (!s.pinned(i)) m = std::max(m, s.v.row(i).norm());
    return m;
}

void describeColliders(const cloth::Collider& c, std::vector<ColliderShape>& out)
{
    if (auto* g = dynamic_cast<const cloth::ColliderGroup*>(&c)) {
        for (const auto& m : g->members)
            if (m) describeColliders(*m, out);
    } else if (auto* p = dynamic_cast<const cloth::PedestalCollider*>(&c)) {
        // #Cylinder: radius 50, height 100 along the scene's y, centred. Drawn
        // 5 mm lower and 3 mm narrower than the collider: the cloth rests on the
        // rounded edge with straight triangle edges (chords) that dip below the
        // true corner, and a full-size cylinder would poke through them.
        const double inset = 3e-3, drop = 5e-3;
        const double r = std::max(p->radius - inset, 0.5 * p->radius), h = std::max(p->height - drop, 0.5 * p->height);
        const Eigen::Vector3d mid = p->top_centre - Eigen::Vector3d(0, 0, p->height - 0.5 * h);
        out.push_back({"pedestal", "#Cylinder", toScene(mid.x(), mid.y(), mid.z()),
                       QVector3D(float(r / 50), float(h / 100), float(r / 50)), QVector3D(0, 1, 0)});
    } else if (auto* s = dynamic_cast<const cloth::SphereCollider*>(&c)) {
        const float k = float(s->radius / 50);
        out.push_back({"sphere", "#Sphere", toScene(s->centre.x(), s->centre.y(), s->centre.z()), QVector3D(k, k, k),
                       QVector3D(0, 1, 0)});
    } else if (auto* pl = dynamic_cast<const cloth::PlaneCollider*>(&c)) {
        // #Rectangle: 100 x 100 units in the scene's xy plane, scaled 3x: 300 m, to the horizon.
        const Eigen::Vector3d n = pl->normal.normalized();
        out.push_back({"plane", "#Rectangle", toScene(pl->point.x(), pl->point.y(), pl->point.z()),
                       QVector3D(3.0f, 3.0f, 1.0f), toScene(n.x(), n.y(), n.z())});
    }
}

} // namespace drape::widget
