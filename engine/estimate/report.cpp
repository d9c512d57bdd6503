#include "engine/estimate/report.hpp"

#include "engine/estimate/detail/report_plots.hpp"

#include "engine/core/error.hpp"
#include "engine/core/io.hpp"
#include "engine/fabric/preset.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <sstream>

namespace drape::estimate {

namespace fs = std::filesystem;
using nlohmann::json;
using namespace detail;

namespace {

constexpr double kPi = std::numbers::pi;

std::string safe(const std::string& id)
{
    std::string s = id;
    for (char& c : s)
        if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_')) c = '_';
    return s;
}

std::string num(double v, const char* f = "%.3g") { return std::isfinite(v) ? fmt(f, v) : std::string("n/a"); }

/// A candidate's fitted amplitude: one number, or "x, y" for the two-column effects.
std::string amplitudes(const EffectCandidate& c)
{
    if (c.amplitudes.size() < 2) return num(c.amplitude);
    std::string s;
    for (double a : c.amplitudes) s += (s.empty() ? "" : ", ") + num(a);
    return s;
}

} // namespace

std::string parameter_table_markdown(const FitResult& r)
{
    std::ostringstream o;
    o << "| parameter | unit | role | value | 95 % interval | constrained | note |\n|---|---|---|---|---|---|---|\n";
    for (const auto& e : r.estimates) {
        o << "| " << e.key << " | " << e.unit << " | " << e.role << " | " << num(e.value) << " | ";
        if (e.role == "fitted") o << num(e.lower95) << " .. " << num(e.upper95);
        else o << "-";
        o << " | " << (e.constrained ? "yes" : "**no**") << " | " << e.note << " |\n";
    }
    return o.str();
}

namespace {

/// The title, the run in one line and what the fit's policies did.
void header_section(std::ostringstream& md, const FitResult& r, const std::string& preset_path)
{
    md << "# Fit report: " << r.name << "\n\n";
    md << "Model `" << to_string(r.options.model) << "`, grid " << r.options.grid << ", seed " << r.options.seed << ", "
       << r.options.seeds_per_evaluation << " perturbation seeds per evaluation. " << r.evaluations << " evaluations, "
       << r.simulations << " simulations, " << num(r.seconds_per_simulation(), "%.2f") << " s per simulation, "
       << num(r.wall_seconds, "%.0f") << " s in all" << (r.cancelled ? " (**cancelled**: best point so far)" : "") << ".\n\n";
    if (r.refinement.from_grid > 0)
        md << "**Grid refinement**: " << r.refinement.reason
           << ". The evaluation and time counts above include both fits.\n\n";
    if (r.anisotropy.assessed && !r.anisotropy.reason.empty()) md << "**Warp/weft bending**: " << r.anisotropy.reason << ".\n\n";
    if (r.shear_hold.assessed && !r.shear_hold.reason.empty()) md << "**Shear**: " << r.shear_hold.reason << ".\n\n";
    if (r.flat_calibration.tried) md << "**The preset draped from flat**: " << r.flat_calibration.reason << ".\n\n";
    if (r.grid_bound)
        md << "**Grid-bound preset**: a fitted bending's bending length is below the mesh spacing of the fit's grid, so the "
              "coarse mesh does part of the bending's work and the preset holds at this mesh density only (`drape predict` keeps "
              "it); fit with a finer `--grid` for a preset that carries over (see the notes in the table).\n\n";
    if (!preset_path.empty()) md << "Preset: `" << preset_path << "`.\n\n";
}

/// The parameter table with its plot and the fitted parameters' correlations.
void parameters_section(std::ostringstream& md, const FitResult& r, const fs::path& root, std::vector<std::string>& files)
{
    md << "## Parameters\n\n" << parameter_table_markdown(r) << "\n";
    parameter_plot(r, (root / "parameters.png").string());
    files.push_back("parameters.png");
    md << "![parameters](parameters.png)\n\n";
    const int n = static_cast<int>(r.variables.size());
    if (n > 1 && r.correlation.size()) {
        md << "Correlations of the fitted (log) parameters:\n\n|   |";
        for (const auto& v : r.variables) md << " " << v.name << " |";
        md << "\n|---|";
        for (int i = 0; i < n; ++i) md << "---|";
        md << "\n";
        for (int i = 0; i < n; ++i) {
            md << "| " << r.variables[i].name << " |";
            for (int k = 0; k < n; ++k) md << " " << num(r.correlation(i, k), "%.2f") << " |";
            md << "\n";
        }
        md << "\n";
    }
}

/// Per record: D and nodes measured and fitted, and the saved preset's own drapes
/// when the flat calibration moved it.
void records_section(std::ostringstream& md, const FitResult& r)
{
    md << "## Records\n\n| record | D1/D2 [mm] | D measured [%] | D fitted [%] | D error | nodes measured | nodes fitted | node error |\n"
          "|---|---|---|---|---|---|---|---|\n";
    for (const auto& rf : r.records)
        md << "| " << rf.measured.id << " | " << num(rf.measured.sample_diameter * 1e3, "%.0f") << "/"
           << num(rf.measured.disc_diameter * 1e3, "%.0f") << " | " << num(rf.measured_features.drape_coefficient_percent, "%.1f")
           << " | " << num(rf.simulated_features.drape_coefficient_percent, "%.1f") << " | " << num(rf.dc_error_percent, "%+.1f")
           << " | " << num(rf.measured_features.node_count, "%.0f") << " | " << num(rf.simulated_features.node_count, "%.1f") << " | "
           << num(rf.node_error, "%+.1f") << " |\n";
    md << "\nMeasured node counts: " << (r.records.empty() ? "" : r.records.front().measured.node_source)
       << "; fitted: the same detector on the simulated drape (mean over the seeds).";
    bool on_branch = false;
    for (const auto& rf : r.records) on_branch = on_branch || rf.branch_folds > 0;
    if (on_branch)
        md << " The fit's cold drapes start on each record's measured fold branch (an n-fold lift of "
           << num(r.options.branch_lift_m * 1e3, "%.0f")
           << " mm, n = the measured node count; `--branch measured`), so D and the contours are compared between drapes with the "
              "record's number of folds; the node error says whether that branch holds at the fitted parameters.";
    md << "\n\n";
    bool moved = false;
    for (const auto& rf : r.records) moved = moved || rf.preset_moved;
    if (moved) {
        // The rows above are the contours' optimum's; the saved preset was moved by
        // the calibration from flat: its own drapes, started as the fit's.
        md << "The preset as saved (calibrated from flat, above: "
           << (r.flat_calibration.fold_search ? "moved along the contours' profile and its bendings " : "its bendings ")
           << num(r.flat_calibration.scale, "%.3f") << " x the optimum's) draped as the fit drapes (warm from the optimum's rest states, the fit's seeds"
           << (on_branch ? ", which started on the record's fold branch" : "") << "), the fitted terms' chi2 "
           << num(r.flat_calibration.chi2_preset, "%.1f") << " against the optimum's " << num(r.chi2, "%.1f") << ":\n\n"
           << "| record | D preset [%] | D error | nodes preset | node error |\n|---|---|---|---|---|\n";
        for (const auto& rf : r.records)
            md << "| " << rf.measured.id << " | " << num(rf.preset_features.drape_coefficient_percent, "%.1f")
               << (rf.preset_converged ? "" : " (not at rest)") << " | " << num(rf.preset_dc_error_percent, "%+.1f") << " | "
               << num(rf.preset_features.node_count, "%.1f") << " | " << num(rf.preset_node_error, "%+.1f") << " |\n";
        md << "\n";
    }
}

/// Records out of the preset's reach: its free strips already drape above them.
void free_strip_section(std::ostringstream& md, const FitResult& r)
{
    bool any = false;
    for (const auto& rf : r.records) any = any || rf.below_free_strips;
    if (!any) return;
    md << "**Out of any drape's reach.** Each radial line of the overhang, alone, is a heavy elastica clamped at the rim; a drape must "
          "also fold or shorten around its circumference, so it lies at or above the D of its free strips. At the preset's bending "
          "(warp "
       << num(r.params[cloth::Param::BendWarp], "%.3g") << ", weft " << num(r.params[cloth::Param::BendWeft], "%.3g")
       << " N*m) the strips alone drape above these records' D, so no drape of this linear bending reaches them:\n\n"
       << "| record | set-up [mm] | D measured [%] | the preset's free strips [%] | the largest bending that drapes to D [N*m] |\n"
          "|---|---|---|---|---|\n";
    for (const auto& rf : r.records)
        if (rf.below_free_strips)
            md << "| " << rf.measured.id << " | " << num(rf.measured.sample_diameter * 1e3, "%.0f") << "/"
               << num(rf.measured.disc_diameter * 1e3, "%.0f") << " | " << num(rf.measured_features.drape_coefficient_percent, "%.1f") << " | "
               << num(rf.free_strip_preset_dc_percent, "%.1f") << " | " << num(rf.free_strip_bound_Nm, "%.2g") << " |\n";
    md << "\nThe records together ask for a bending that changes with the drape's scale, or carry an effect of their set-up the model "
          "lacks; fitted alone, such a record gets a bending below its bound (docs/model-discrepancy.md, \"The free-strip bound\").\n\n";
}

/// The preset draped from flat, as predict, compare and the widget drape it, on the
/// fit's grid and a finer one.
void from_flat_section(std::ostringstream& md, const FitResult& r)
{
    bool on_branch = false;
    for (const auto& rf : r.records) on_branch = on_branch || rf.branch_folds > 0;
    if (r.records.empty() || r.records.front().cold_seeds <= 0) return;
    md << "The fit's simulations start from the rest state of the best point so far (warm)"
       << (on_branch ? " or on the measured fold branch" : "")
       << ". Draped from flat with the random mix of modes, as `drape predict`, `drape compare` and the widget drape it (mean of "
       << r.records.front().cold_seeds << " perturbation seeds"
       << (r.options.laying_load < 1 ? ", laid under " + num(r.options.laying_load, "%.2f") +
                                           " g first as the records' lab is assumed to lay them (`--laying`, written into the preset)"
                                     : std::string(", the whole load at once"))
       << ", the flat start's waviness " << num(r.options.perturbation_m * 1e3, "%.1f") << " mm (`--perturbation`, written into the preset)"
       << "), the preset"
       << (r.flat_calibration.applied ? (r.flat_calibration.fold_search ? " (moved along the contours' profile and its bendings " : " (its bendings ") +
                                            num(r.flat_calibration.scale, "%.3f") + " x the contours' optimum: calibrated from flat, above)"
                                      : std::string())
       << " gives"
       << (on_branch ? " (the fold count a random start picks can differ from the record's: a bifurcation, not a misfit)" : "")
       << ":\n\n"
       << "| record | D cold [%] | D error cold | nodes cold | node error cold |";
    // The first seed again on a finer grid (FitOptions::flat_check_grid): does
    // the preset carry over to a CAD's finer mesh?
    int fine = 0;
    double fine_diameter = 0;
    for (const auto& rf : r.records)
        if (rf.cold_fine_grid > fine) {
            fine = rf.cold_fine_grid;
            fine_diameter = rf.measured.sample_diameter;
        }
    if (fine > 0) md << " D at grid " << fine << " [%] | D error | nodes | node error |";
    md << "\n|---|---|---|---|---|" << (fine > 0 ? "---|---|---|---|" : "") << "\n";
    for (const auto& rf : r.records) {
        md << "| " << rf.measured.id << " | " << num(rf.cold_features.drape_coefficient_percent, "%.1f") << " | "
           << num(rf.cold_dc_error_percent, "%+.1f") << " | " << num(rf.cold_features.node_count, "%.1f") << " | "
           << num(rf.cold_node_error, "%+.1f") << " |";
        if (fine > 0) {
            if (rf.cold_fine_grid > 0)
                md << " " << num(rf.cold_fine_features.drape_coefficient_percent, "%.1f") << (rf.cold_fine_converged ? "" : " (not at rest)")
                   << " | " << num(rf.cold_fine_dc_error_percent, "%+.1f") << " | " << num(rf.cold_fine_features.node_count, "%.0f") << " | "
                   << num(rf.cold_fine_node_error, "%+.0f") << " |";
            else
                md << " - | - | - | - |";
        }
        md << "\n";
    }
    if (fine > 0)
        md << "\nAt grid " << fine << " the first seed (grid " << r.options.grid
           << " cells are " << num(fine_diameter * 1e3 / std::max(1, r.options.grid - 1), "%.1f")
           << " mm, grid " << fine << " " << num(fine_diameter * 1e3 / std::max(1, fine - 1), "%.1f")
           << " mm): a preset that is the fabric, not the fit's mesh, drapes alike on both (`drape simulate --grid " << fine << "`).\n";
    md << "\n";
}

/// Per record: its plots, the contours per depth and the sensitivity of D; the
/// details for report.json.
json record_sections(std::ostringstream& md, const FitResult& r, const fs::path& root, std::vector<std::string>& files)
{
    json recs = json::array();
    for (int i = 0; i < static_cast<int>(r.records.size()); ++i) {
        const auto& rf = r.records[i];
        const std::string id = safe(rf.measured.id);
        const double rot = best_rotation(rf);
        md << "### " << rf.measured.id << "\n\n";
        if (top_overlay(rf, rot, (root / (id + "_top_overlay.png")).string())) {
            files.push_back(id + "_top_overlay.png");
            md << "![top overlay](" << id << "_top_overlay.png)\n\n";
        }
        if (rf.measured.contours.empty()) {
            md << "No laser contours: fitted from the photos (drape coefficient, nodes, hem height).\n\n";
        } else {
            outline_plot(rf, rot, (root / (id + "_contours.png")).string());
            r_theta_plot(rf, rot, (root / (id + "_r_theta.png")).string());
            harmonic_plot(r, i, (root / (id + "_harmonics.png")).string());
            files.insert(files.end(), {id + "_contours.png", id + "_r_theta.png", id + "_harmonics.png"});
            md << "![contours](" << id << "_contours.png)\n\n![r(theta)](" << id << "_r_theta.png)\n\n![harmonics](" << id
               << "_harmonics.png)\n\n";
        }
        if (!rf.measured_features.contours.empty())
            md << "| depth [mm] | mean r measured / fitted [mm] | RMS fold amplitude measured / fitted [mm] | nodes measured / fitted |\n|---|---|---|---|\n";
        json depths = json::array();
        for (std::size_t d = 0; d < rf.measured_features.contours.size(); ++d) {
            const auto& m = rf.measured_features.contours[d];
            const auto& s = rf.simulated_features.contours[d];
            md << "| " << num(m.depth_m * 1e3, "%.0f") << " | " << num(m.mean_radius_m * 1e3, "%.1f") << " / "
               << num(s.mean_radius_m * 1e3, "%.1f") << " | " << num(m.fold_rms_m * 1e3, "%.2f") << " / " << num(s.fold_rms_m * 1e3, "%.2f")
               << " | " << m.node_count << " / " << s.node_count << " |\n";
            depths.push_back({{"depth_m", m.depth_m},
                              {"measured_mean_radius_m", m.mean_radius_m},
                              {"fitted_mean_radius_m", s.mean_radius_m},
                              {"measured_fold_rms_m", m.fold_rms_m},
                              {"fitted_fold_rms_m", s.fold_rms_m},
                              {"measured_harmonic_magnitudes_m", m.magnitudes_m},
                              {"fitted_harmonic_magnitudes_m", s.magnitudes_m}});
        }
        md << "\n";
        json dsens = json::object();
        if (!rf.d_drape_per_10_percent.empty()) {
            md << "Sensitivity of D at the optimum (exact, from the rest state's Hessian): D change for +10 % of each "
                  "fitted parameter.\n\n| parameter | value | D change [points] |\n|---|---|---|\n";
            for (const auto& [q, d] : rf.d_drape_per_10_percent) {
                const auto& sp = cloth::spec(q);
                md << "| " << sp.key << " | " << num(r.params[q], "%.3g") << " " << sp.unit << " | " << num(d, "%+.2f") << " |\n";
                dsens[std::string(sp.key)] = d;
            }
            md << "\n";
        }
        recs.push_back({{"id", rf.measured.id},
                        {"rotation_for_plots_deg", rot * 180 / kPi},
                        {"depths", depths},
                        {"d_drape_coefficient_per_10_percent", dsens}});
    }
    return recs;
}

/// The search's trace with its plot.
void convergence_section(std::ostringstream& md, const FitResult& r, const fs::path& root, std::vector<std::string>& files)
{
    if (!r.trace.empty()) {
        md << "## Convergence\n\nMethod `" << to_string(r.options.method) << "`: " << r.evaluations << " evaluations ("
           << r.simulations << " drapes), " << r.factorisations << " Hessian factorisations and " << r.back_substitutions
           << " back-substitutions for exact sensitivities, " << r.jacobians << " Jacobians"
           << (r.jacobian_jumps > 0 ? " (" + std::to_string(r.jacobian_jumps) +
                                          " of their entries left at 0: the feature jumped between the difference's points, its slopes at the step and at half "
                                          "of it disagreeing)"
                                    : std::string())
           << ".\n\n";
        convergence_plot(r, (root / "convergence.png").string());
        files.push_back("convergence.png");
        md << "![convergence](convergence.png)\n\n| evaluation | stage | chi2 | best so far | coordinates (";
        for (std::size_t i = 0; i < r.variables.size(); ++i) md << (i ? ", " : "") << (r.variables[i].log_scale ? "log10 " : "") << r.variables[i].name;
        md << ") | time [s] |\n|---|---|---|---|---|---|\n";
        for (const auto& t : r.trace) {
            md << "| " << t.evaluation << " | " << t.stage << " | " << num(t.chi2, "%.1f") << " | " << num(t.best_chi2, "%.1f") << " | ";
            for (std::size_t i = 0; i < t.coords.size(); ++i) md << (i ? ", " : "") << num(t.coords[i], "%.3f");
            md << " | " << num(t.elapsed_s, "%.1f") << " |\n";
        }
        md << "\n";
    }
}

/// The candidate effects, chi2 and the residual's structure, and the noise model.
void residual_section(std::ostringstream& md, const FitResult& r, const fs::path& root, std::vector<std::string>& files)
{
    const ResidualAnalysis& a = r.residual;
    md << "## Residual analysis\n\n";
    if (r.residual.candidates.empty() && !r.residual.unexplained.empty()) md << "Candidate effects: " << r.residual.unexplained << ".\n\n";
    if (!r.residual.candidates.empty()) {
        md << "### Candidate effects (engine-made signatures, docs/model-discrepancy.md)\n\n";
        md << (r.residual.named_effect.empty() ? std::string("Named effect: **none**") : "Named effect: **" + r.residual.named_effect + "**");
        if (!r.residual.unexplained.empty()) md << " (" << r.residual.unexplained << ")";
        md << ".\n\n";
        candidates_plot(r, (root / "candidates.png").string());
        files.push_back("candidates.png");
        md << "![candidate effects](candidates.png)\n\n";
        md << "| effect | family | parameters | z | delta chi2 | information | amplitude | verdict | note |\n|---|---|---|---|---|---|---|---|---|\n";
        for (const auto& c : r.residual.candidates) {
            md << "| " << c.name << " | " << c.family << " | " << c.parameters << " | ";
            if (c.verdict == "not testable") md << "- | - | - | - | ";
            else
                md << num(c.z, "%+.2f") << " | " << num(c.delta_chi2, "%.2f") << " | " << num(c.information, "%+.2f") << " | "
                   << amplitudes(c) << " " << c.amplitude_unit << " | ";
            md << c.verdict << " | " << c.note << " |\n";
        }
        md << "\n";
    }
    md << "chi2 = " << num(a.chi2, "%.1f") << " for " << a.dof << " degrees of freedom (RMS whitened residual "
       << num(a.rms_whitened, "%.2f") << "; 1 = at the noise): the residual **" << (a.exceeds_noise ? "exceeds" : "is within")
       << "** the measurement noise. RMS contour residual " << num(a.rms_m * 1e3, "%.2f") << " mm.\n\n";
    if (!a.exceeds_because.empty()) {
        md << "Beyond noise by (each test at about 3 sigma of its own statistic):";
        for (const auto& b : a.exceeds_because) md << "\n- " << b;
        md << "\n\n";
    }
    for (const auto& [k, z] : a.signature_z)
        md << "Matched filter `" << k << "`: z = " << num(z, "%.2f") << " (above 3: the residual has that effect's shape).\n\n";
    md << "| channel | whitened RMS |\n|---|---|\n";
    for (const auto& [k, v] : a.kind_rms) md << "| " << k << " | " << num(v, "%.2f") << " |\n";
    md << "\nDominant harmonics (whitened RMS > 2): ";
    if (a.dominant_harmonics.empty()) md << "none";
    for (int k : a.dominant_harmonics) md << k << " ";
    md << "\n\n";
    // The matched filters are a first screen; when the candidate library ran, its
    // verdict (named effect, or unexplained) above is the report's word on the
    // cause, and this paragraph must not contradict it.
    const bool library_ran = !r.residual.candidates.empty();
    if (a.candidate_effects.empty()) {
        if (library_ran)
            md << "Matched filters: no signature above 3 sigma (the candidate effects' refits above decide what is named).\n";
        else
            md << "No candidate effect: the model explains the record(s) to the noise level"
               << (a.exceeds_noise ? " as far as the signatures checked can tell" : "") << ".\n";
    } else if (library_ran) {
        md << "Matched filters above 3 sigma (a screen; the refits above decide what is named):\n";
    }
    for (std::size_t i = 0; i < a.candidate_effects.size(); ++i) md << "- **" << a.candidate_effects[i] << "**: " << a.evidence[i] << "\n";
    md << "\nNoise model (1 sigma): laser " << num(r.options.noise.laser_m * 1e3, "%.2f") << " mm per point, D "
       << num(r.options.noise.dc_lab_percent, "%.1f") << " % (drapemeter) + " << num(r.options.noise.dc_seed_percent, "%.1f")
       << " % (drape-to-drape), nodes " << num(r.options.noise.nodes, "%.2f") << ", contour mean radius "
       << num(r.options.noise.radius_seed_m * 1e3, "%.1f") << " mm, fold amplitude / harmonic magnitudes "
       << num(r.options.noise.fold_seed_m * 1e3, "%.1f") << " mm (defaults; each term's sigma is then multiplied by sqrt(1 + 1/seeds), contour floors by sqrt(depths), and raised to the drape-to-drape spread measured at the optimum: see the `sigma` of each term in report.json and docs/estimate.md).\n";
}

} // namespace

std::vector<std::string> write_fit_report(const FitResult& r, const std::string& dir, const std::string& preset_path)
{
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) throw FileError(dir + ": cannot create the report folder (" + ec.message() + ")");
    std::vector<std::string> files;
    const fs::path root(dir);
    std::ostringstream md;
    header_section(md, r, preset_path);
    parameters_section(md, r, root, files);
    records_section(md, r);
    from_flat_section(md, r);
    free_strip_section(md, r);
    const json recs = record_sections(md, r, root, files);
    convergence_section(md, r, root, files);
    residual_section(md, r, root, files);

    json rep = fit_to_json(r);
    rep["records_detail"] = recs;
    json terms = json::array();
    for (const auto& t : r.residuals)
        terms.push_back({{"record", t.record}, {"kind", t.kind}, {"depth_m", t.depth_m}, {"harmonic", t.harmonic}, {"simulated", t.simulated},
                         {"measured", t.measured}, {"sigma", t.sigma}, {"whitened", t.whitened()}, {"fitted", t.fitted}});
    rep["residual_terms"] = terms;
    drape::write_file_atomic((root / "report.json").string(), rep.dump(2) + "\n");
    drape::write_file_atomic((root / "report.md").string(), md.str());
    files.push_back("report.json");
    files.push_back("report.md");
    return files;
}

} // namespace drape::estimate
