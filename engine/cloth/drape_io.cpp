#include "engine/cloth/drape_io.hpp"

#include "engine/core/error.hpp"
#include "engine/core/io.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <sstream>

namespace drape::cloth {

using nlohmann::json;

namespace {
double deg(double rad) { return rad * 180.0 / std::numbers::pi; }
json num_or_null(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }
} // namespace

json drape_summary_json(const DrapeResult& r, const DrapeSetup& setup, Integrator integ)
{
    const auto& m = r.metrics;
    json j;
    j["drape_coefficient_percent"] = m.drape_coefficient_percent;
    j["node_count"] = m.node_count;
    json angles = json::array(), amps = json::array();
    for (double a : m.node_angles_rad) angles.push_back(deg(a));
    for (double a : m.node_amplitudes_m) amps.push_back(a);
    j["node_angles_deg"] = angles;
    j["node_amplitudes_m"] = amps;
    j["shadow_area_m2"] = m.shadow_area_m2;
    j["potential_energy_J"] = r.potential_energy;
    j["mean_radius_m"] = m.mean_radius_m;
    j["min_radius_m"] = m.min_radius_m;
    j["max_radius_m"] = m.max_radius_m;
    j["hem_min_height_m"] = r.hem.min_z;
    j["hem_max_height_m"] = r.hem.max_z;
    j["hem_mean_height_m"] = r.hem.mean_z;
    json harm = json::array();
    for (int k = 1; k <= std::min(12, m.fourier.harmonics()); ++k) harm.push_back(m.fourier.magnitude(k));
    j["outline_harmonic_magnitudes_m"] = harm;
    json slices = json::array();
    for (const auto& s : r.slices) {
        json sj;
        sj["depth_m"] = s.depth_m;
        sj["closed"] = s.profile.complete();
        if (s.profile.complete()) {
            const FourierSeries f = fourier_fit(s.profile, 12);
            sj["mean_radius_m"] = f.a0;
            json mags = json::array();
            for (int k = 1; k <= f.harmonics(); ++k) mags.push_back(f.magnitude(k));
            sj["harmonic_magnitudes_m"] = mags;
        }
        slices.push_back(sj);
    }
    j["slices"] = slices;
    j["converged"] = r.status.converged();
    j["status"] = to_string(r.status.outcome);
    if (!r.status.message.empty()) j["status_message"] = r.status.message;
    j["solver"] = to_string(integ);
    j["steps"] = r.status.steps;
    j["newton_iterations"] = r.status.newton_iterations;
    j["force_evaluations"] = r.status.force_evaluations;
    j["residual_relative"] = num_or_null(r.status.residual);
    j["max_speed_m_s"] = num_or_null(r.status.max_speed);
    j["simulated_time_s"] = r.status.sim_time;
    j["wall_seconds"] = r.status.wall_seconds;
    j["sample_diameter_m"] = setup.sample_diameter;
    j["disc_diameter_m"] = setup.disc_diameter;
    j["grid"] = setup.grid;
    j["mesh"] = to_string(setup.mesh);
    j["seed"] = setup.seed;
    j["perturbation_m"] = setup.perturbation;
    j["fold_mode"] = setup.fold_mode; // 0: the seeded mix of modes; n: started on the n-fold branch
    // One crest of the n-fold start this far from the warp (null: the seeded phase).
    j["fold_angle_deg"] = setup.fold_mode >= 2 && std::isfinite(setup.fold_angle) ? nlohmann::json(setup.fold_angle * 180 / std::numbers::pi)
                                                                                  : nlohmann::json(nullptr);
    // Fraction of gravity of the first rest (1: the whole load at once); the
    // dynamic integrators fall under the whole load.
    j["laying_load"] = integ == Integrator::Static ? setup.laying_load : 1.0;
    j["vertices"] = r.x.rows();
    return j;
}

void write_obj(const std::string& path, const Positions& X, const Triangles& F, const Eigen::MatrixX2d* uv)
{
    std::ostringstream o;
    o.precision(9);
    o << "# Drapekit rest mesh, metres, z up\n";
    for (int i = 0; i < X.rows(); ++i) o << "v " << X(i, 0) << ' ' << X(i, 1) << ' ' << X(i, 2) << '\n';
    if (uv)
        for (int i = 0; i < uv->rows(); ++i) o << "vt " << (*uv)(i, 0) << ' ' << (*uv)(i, 1) << '\n';
    for (int t = 0; t < F.rows(); ++t) {
        o << 'f';
        for (int c = 0; c < 3; ++c) {
            o << ' ' << F(t, c) + 1;
            if (uv) o << '/' << F(t, c) + 1;
        }
        o << '\n';
    }
    write_file_atomic(path, o.str());
}

void write_slices_csv(const std::string& path, const DrapeResult& r)
{
    std::ostringstream o;
    o.precision(9);
    o << "depth_m,theta_deg,r_m,x_m,y_m\n";
    for (const auto& s : r.slices)
        for (int k = 0; k < s.profile.size(); ++k) {
            const double rr = s.profile.r[static_cast<std::size_t>(k)];
            if (!std::isfinite(rr)) continue;
            const double th = s.profile.theta(k);
            o << s.depth_m << ',' << deg(th) << ',' << rr << ',' << rr * std::cos(th) << ',' << rr * std::sin(th) << '\n';
        }
    write_file_atomic(path, o.str());
}

void write_outline_csv(const std::string& path, const DrapeResult& r)
{
    std::ostringstream o;
    o.precision(9);
    o << "theta_deg,r_m\n";
    const auto& p = r.metrics.profile;
    for (int k = 0; k < p.size(); ++k) o << deg(p.theta(k)) << ',' << p.r[static_cast<std::size_t>(k)] << '\n';
    write_file_atomic(path, o.str());
}

void write_drape_outputs(const std::string& dir, const DrapeResult& r, const DrapeSetup& setup, Integrator integ, const ClothMesh& mesh)
{
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) throw FileError(dir + ": cannot create output folder (" + ec.message() + ")");
    write_file_atomic(dir + "/summary.json", drape_summary_json(r, setup, integ).dump(2) + "\n");
    write_obj(dir + "/rest.obj", r.x, mesh.F, &mesh.uv);
    write_slices_csv(dir + "/slices.csv", r);
    write_outline_csv(dir + "/outline.csv", r);
}

} // namespace drape::cloth
