#include "widget/drape_results.hpp"

#include "engine/cloth/drape_io.hpp"
#include "engine/core/error.hpp"
#include "engine/core/io.hpp"
#include "engine/fabric/preset.hpp"

#include <QFileInfo>

#include <nlohmann/json.hpp>

namespace drape::widget {

QString saveDrapeResults(const QString& jsonPath, const cloth::ClothSystem& sys, const DrapeSpec& spec,
                         const SolverSettings& solver, const std::vector<float>& texcoord)
{
    if (jsonPath.isEmpty()) throw FileError("save results: empty file name");
    const QFileInfo fi(jsonPath);
    const QString objPath = fi.path() + QLatin1Char('/') + fi.completeBaseName() + QStringLiteral(".obj");
    const cloth::ClothMesh& mesh = sys.mesh();

    nlohmann::json j;
    j["format"] = "drapekit-widget-state";
    j["version"] = 1;
    j["fabric_preset"] = spec.presetName.toStdString();
    j["fabric"] = fabric::fabric_to_json(spec.preset);
    const cloth::DrapeSetup& su = spec.setup;
    j["setup"] = {{"shape", toString(spec.shape).toStdString()},
                  {"sample_diameter_m", su.sample_diameter},
                  {"disc_diameter_m", su.disc_diameter},
                  {"pedestal_height_m", su.pedestal_height},
                  {"grid", su.grid},
                  {"seed", su.seed},
                  {"floor", su.floor}};
    j["solver"] = {{"integrator", solver.integrator.toStdString()},
                   {"time_step_s", solver.timeStep},
                   {"rest_speed_m_s", solver.restSpeed},
                   {"rest_residual", solver.restResidual}};
    j["state"] = {{"sim_time_s", sys.time},
                  {"steps", solver.steps},
                  {"vertices", sys.vertex_count()},
                  {"triangles", mesh.F.rows()},
                  {"max_speed_m_s", maxFreeSpeed(sys)},
                  {"relative_residual", cloth::relative_residual(sys, solver.integrator == QLatin1String("implicit") ||
                                                                              solver.integrator == QLatin1String("static"))},
                  {"obj", QFileInfo(objPath).fileName().toStdString()}};
    std::vector<int> pinned;
    for (int i = 0; i < sys.vertex_count(); ++i)
        if (sys.pinned(i)) pinned.push_back(i);
    j["state"]["pinned"] = pinned;
    j["state"]["total_mass_kg"] = sys.model().total_mass();

    if (!isDrapemeter(spec.shape)) {
        // A garment: its extent; the drapemeter's metrics do not apply.
        j["results"] = {{"min_z_m", sys.x.col(2).minCoeff()}, {"max_z_m", sys.x.col(2).maxCoeff()}};
    } else {
    const cloth::DrapeResult r = cloth::measure_drape(sys, su);
    nlohmann::json outline = nlohmann::json::array();
    for (const auto& p : r.outline) outline.push_back({p.x(), p.y()});
    j["results"] = {{"shadow_area_m2", r.metrics.shadow_area_m2},
                    {"drape_coefficient_percent", r.metrics.drape_coefficient_percent},
                    {"node_count", r.metrics.node_count},
                    {"node_angles_rad", r.metrics.node_angles_rad},
                    {"mean_radius_m", r.metrics.mean_radius_m},
                    {"min_radius_m", r.metrics.min_radius_m},
                    {"max_radius_m", r.metrics.max_radius_m},
                    {"hem_min_z_m", r.hem.min_z},
                    {"hem_max_z_m", r.hem.max_z},
                    {"outline_m", outline}};
    }

    // The OBJ's texture coordinates are the ones the view maps the texture with.
    Eigen::MatrixX2d vt(sys.vertex_count(), 2);
    for (int i = 0; i < sys.vertex_count(); ++i)
        for (int k = 0; k < 2; ++k)
            vt(i, k) = texcoord.size() == std::size_t(2 * sys.vertex_count()) ? double(texcoord[std::size_t(2 * i + k)]) : 0.0;
    cloth::write_obj(objPath.toStdString(), sys.x, mesh.F, &vt);
    write_file_atomic(jsonPath.toStdString(), j.dump(2) + "\n");
    return objPath;
}

} // namespace drape::widget
