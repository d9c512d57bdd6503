#include "widget/drape_setup.hpp"

#include "engine/cloth/colliders.hpp"
#include "engine/cloth/model.hpp"
#include "engine/core/error.hpp"

#include <algorithm>

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

} // namespace

std::unique_ptr<cloth::ClothSystem> makeDrapeSystem(const DrapeSpec& spec)
{
    std::unique_ptr<cloth::ClothSystem> sys;
    if (spec.shape == QLatin1String("square"))
        sys = makeSquareSystem(spec.preset, spec.setup);
    else if (spec.shape == QLatin1String("disc"))
        sys = cloth::make_drape_system(spec.preset.material(), spec.setup, spec.preset.model);
    else
        throw ParameterError("shape: unknown cloth shape '" + spec.shape.toStdString() + "' (use disc or square)");
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
