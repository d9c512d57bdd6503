#pragma once
// Output files of a drape: JSON summary, rest mesh (OBJ), slices and outline (CSV).
#include "engine/cloth/drape.hpp"

#include <nlohmann/json.hpp>

#include <string>

namespace drape::cloth {

/// The summary `drape simulate --json` prints (keys carry their units).
nlohmann::json drape_summary_json(const DrapeResult& r, const DrapeSetup& setup, Integrator integ);

/// Wavefront OBJ of positions [m] and triangles (1-based indices), with uv as vt.
void write_obj(const std::string& path, const Positions& X, const Triangles& F, const Eigen::MatrixX2d* uv = nullptr);

/// slices.csv: depth_m,theta_deg,r_m,x_m,y_m (rays that miss are skipped).
void write_slices_csv(const std::string& path, const DrapeResult& r);

/// outline.csv: theta_deg,r_m of the shadow outline.
void write_outline_csv(const std::string& path, const DrapeResult& r);

/// Writes summary.json, rest.obj, slices.csv and outline.csv into `dir` (created).
void write_drape_outputs(const std::string& dir, const DrapeResult& r, const DrapeSetup& setup, Integrator integ,
                         const ClothMesh& mesh);

} // namespace drape::cloth
