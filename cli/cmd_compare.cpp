// drape compare: simulate a preset on the set-up of measured records and
// compare, channel by channel, without fitting anything. Used to check a
// preset against records it was not fitted to, and to predict the signature
// of a model change (docs/model-discrepancy.md).
#include "cli/command.hpp"
#include "cli/checks.hpp"
#include "cli/setup.hpp"

#include "engine/core/error.hpp"
#include "engine/core/units.hpp"
#include "engine/fabric/preset.hpp"
#include "engine/cloth/blas_threads.hpp"
#include "engine/estimate/fit.hpp"
#include "engine/estimate/objective.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>

namespace drape::cli {
namespace cmd_compare {

const char* kUsage = R"(usage: drape compare RECORD_DIR [RECORD_DIR ...] --fabric FABRIC.json [options]

Simulates the preset on each record's own set-up (specimen and disc diameters,
areal density and thickness from the record) and compares it with the record,
channel by channel, as `drape fit` does - but fits nothing. Use it to check a
preset against records it was not fitted to, or to see what a model change does.

  --fabric F            a drapekit-fabric preset: file, library name or starter (silk, cotton, ...)
  --set KEY=VALUE       override one parameter (a key of the parameter table; repeatable)
  --grid N              nodes across a 300 mm specimen, scaled with the diameter (default: the grid
                        the preset was fitted at, provenance.grid, as drape fit compared it; else 25)
  --mesh M              grid | rings (default: the fit's, provenance.mesh, else grid)
  --seeds S             perturbation seeds averaged (default 2)
  --seed K              first perturbation seed (default 1)
  --branch B            where the drapes start: random (default; the seeded mix of modes, as
                        `drape predict`) or measured (an n-fold lift, n = the record's node count,
                        as `drape fit` drapes)
  --laying F            random branch: the first rest under the fraction F of gravity, then all of
                        it (default: the preset's provenance.laying_load, as drape simulate; else 1)
  --perturbation L      random branch: the largest lift of the flat start's waviness (default: the
                        preset's provenance.perturbation_m, as drape simulate; else 1mm)
  --disc-grip           the specimen cannot slide on the disc top (large static friction)
  --vertex-contact-only contact at mesh vertices only (the seed's; coarse elements cut the rim)
  --json                print the comparison as JSON on stdout
  --quiet               no progress on stderr

Prints per record: D, node count and hem (simulated, measured, difference),
and per contour depth the mean radius and RMS fold amplitude differences
(simulated - measured) in mm, and chi2 of the residual with the default noise
model (the fit's before its drape-to-drape calibration, so chi2 differs from a fit's).)";

/// Refuses a comparison that cannot be right (a term that is not finite), naming the term.
void check_finite(const std::string& id, const std::vector<estimate::ResidualTerm>& terms, double chi2)
{
    if (!std::isfinite(chi2)) {
        std::string which;
        for (const auto& t : terms)
            if (!std::isfinite(t.whitened())) {
                which = t.kind + (t.depth_m > 0 ? " at depth " + format_value(t.depth_m * 1e3) + " mm" : std::string()) +
                        ": simulated " + format_value(t.simulated) + ", measured " + format_value(t.measured);
                break;
            }
        throw Error(id + ": the comparison's chi2 is not finite (" + which + ")");
    }
}

/// One record's comparison: D, nodes, the hem and every depth's errors.
nlohmann::json comparison_json(const std::string& id, int grid, cloth::DrapeMesh mesh, int seeds, int folds, double chi2,
                               const std::vector<estimate::ResidualTerm>& terms, const estimate::DrapeFeatures& meas,
                               const estimate::DrapeFeatures& sim, const std::vector<double>& closed)
{
    nlohmann::json rec = {{"record", id},
                          {"grid", grid},
                          {"mesh", cloth::to_string(mesh)},
                          {"seeds", seeds},
                          {"fold_branch", folds > 0 ? nlohmann::json(folds) : nlohmann::json(nullptr)},
                          {"chi2", chi2},
                          {"terms", static_cast<int>(terms.size())}};
    nlohmann::json depths = nlohmann::json::array();
    for (const auto& t : terms) {
        if (t.kind == "dc")
            rec["drape_coefficient_percent"] = {{"simulated", t.simulated}, {"measured", t.measured}, {"error", t.simulated - t.measured}};
        else if (t.kind == "nodes")
            rec["node_count"] = {{"simulated", t.simulated}, {"measured", t.measured}, {"error", t.simulated - t.measured}};
        else if (t.kind == "hem")
            rec["hem_min_z_m"] = {{"simulated", t.simulated}, {"measured", t.measured}, {"error", t.simulated - t.measured}};
    }
    // Radii of a simulated slice that does not close in any seed are not a
    // contour (a cut through a few triangles): no error is computed for
    // that depth; it is reported as not closed. The RMS runs over the
    // depths that closed.
    int unclosed = 0;
    double sr = 0, sf = 0;
    int n_closed = 0;
    for (std::size_t d = 0; d < meas.contours.size() && d < sim.contours.size(); ++d) {
        const auto& mc = meas.contours[d];
        const auto& sc = sim.contours[d];
        const double cf = d < closed.size() ? closed[d] : 0.0;
        nlohmann::json dj = {{"depth_m", mc.depth_m}, {"closed_fraction", cf}, {"closed", cf > 0}};
        const double er = sc.mean_radius_m - mc.mean_radius_m, ef = sc.fold_rms_m - mc.fold_rms_m;
        if (cf > 0 && std::isfinite(er) && std::isfinite(ef)) {
            dj["mean_radius_error_m"] = er;
            dj["fold_rms_error_m"] = ef;
            dj["cos2_error_m"] = sc.cos2_m - mc.cos2_m;
            sr += er * er;
            sf += ef * ef;
            ++n_closed;
        } else {
            dj["mean_radius_error_m"] = nullptr;
            dj["fold_rms_error_m"] = nullptr;
            dj["cos2_error_m"] = nullptr;
            ++unclosed;
        }
        depths.push_back(dj);
    }
    rec["depths"] = depths;
    rec["unclosed_depths"] = unclosed;
    if (n_closed > 0) {
        rec["mean_radius_rms_error_m"] = std::sqrt(sr / n_closed);
        rec["fold_rms_rms_error_m"] = std::sqrt(sf / n_closed);
    }
    return rec;
}

/// One record's comparison for a person.
void print_comparison(const nlohmann::json& rec, const std::vector<estimate::ResidualTerm>& terms)
{
    const std::string id = rec["record"].get<std::string>();
    const int grid = rec["grid"].get<int>(), seeds = rec["seeds"].get<int>();
    const int folds = rec["fold_branch"].is_null() ? 0 : rec["fold_branch"].get<int>();
    const int unclosed = rec["unclosed_depths"].get<int>();
    const nlohmann::json& depths = rec["depths"];
    auto v = [&](const char* k, const char* f) { return rec.contains(k) ? rec[k][f].get<double>() : NAN; };
    std::printf("%s  grid %d, %d seeds%s, chi2 %.1f over %zu terms\n", id.c_str(), grid, seeds,
                folds > 0 ? (", started on the measured " + std::to_string(folds) + "-fold branch").c_str() : "",
                rec["chi2"].get<double>(), terms.size());
    std::printf("  D      sim %5.1f %%  meas %5.1f %%  err %+5.1f\n", v("drape_coefficient_percent", "simulated"),
                v("drape_coefficient_percent", "measured"), v("drape_coefficient_percent", "error"));
    std::printf("  nodes  sim %5.1f    meas %5.1f    err %+5.1f\n", v("node_count", "simulated"), v("node_count", "measured"),
                v("node_count", "error"));
    if (rec.contains("free_strip") && rec["free_strip"]["below"].get<bool>())
        std::printf("  out of reach: the preset's free strips alone drape to %.1f %% here, above the record's %.1f %%; no drape of its "
                    "bending gets down to it (the record allows at most %.2g N*m; docs/model-discrepancy.md, the free-strip bound)\n",
                    rec["free_strip"]["preset_drape_coefficient_percent"].get<double>(), v("drape_coefficient_percent", "measured"),
                    rec["free_strip"]["bending_bound_Nm"].get<double>());
    if (rec.contains("hem_min_z_m"))
        std::printf("  hem    sim %5.1f mm meas %5.1f mm err %+5.1f mm\n", 1e3 * v("hem_min_z_m", "simulated"),
                    1e3 * v("hem_min_z_m", "measured"), 1e3 * v("hem_min_z_m", "error"));
    if (rec.contains("mean_radius_rms_error_m"))
        std::printf("  contours: RMS over the closed depths of the mean-radius error %.2f mm, of the fold-amplitude error %.2f mm\n",
                    1e3 * rec["mean_radius_rms_error_m"].get<double>(), 1e3 * rec["fold_rms_rms_error_m"].get<double>());
    if (unclosed > 0)
        std::printf("  %d depth(s) where the simulated slice does not close (the drape does not reach that deep all round):"
                    " no radius error there; chi2 counts them as closure misses\n",
                    unclosed);
    std::printf("  depth [mm]  mean radius err [mm]  fold RMS err [mm]\n");
    for (const auto& d : depths) {
        if (d["mean_radius_error_m"].is_null()) {
            std::printf("  %6.0f      not closed\n", 1e3 * d["depth_m"].get<double>());
            continue;
        }
        std::printf("  %6.0f      %+6.2f                %+6.2f%s\n", 1e3 * d["depth_m"].get<double>(),
                    1e3 * d["mean_radius_error_m"].get<double>(), 1e3 * d["fold_rms_error_m"].get<double>(),
                    d["closed_fraction"].get<double>() < 1 ? "   (closed in some seeds only)" : "");
    }
}

int run(const std::vector<std::string>& argv)
{
    Args a(argv, fabric_flags() + setup_value_flags(kGrid | kSeed | kLaying | kMesh | kPerturbation) + std::set<std::string>{"--seeds", "--branch"},
           setup_switches(kDiscGrip) + std::set<std::string>{"--json", "--quiet", "--vertex-contact-only"});
    if (a.positionals().empty()) throw UsageError("at least one RECORD_DIR is required");
    reject_duplicate_records(a.positionals());
    const fabric::FabricPreset preset = load_fabric_flags(a);
    if (preset.is_seed())
        throw UsageError("--fabric: " + *a.get("--fabric") + " is a seed-19 preset; compare needs a drapekit-fabric preset");
    const cloth::FabricParams* base = &preset.params;
    // The fit's mesh density at 300 mm (provenance.grid is the fit's, at its own
    // first record's diameter) and its mesh: the preset is compared as it was fitted.
    const auto fit_grid300 = preset_fit_grid(preset, 0.30);
    const int grid300 = a.get_int("--grid", fit_grid300 ? std::clamp(*fit_grid300, 9, 200) : 25, 9, 200);
    const cloth::DrapeMesh mesh = preset_mesh(a, preset);
    const int seeds = a.get_int("--seeds", 2, 1, 16);
    const auto seed0 = static_cast<std::uint64_t>(a.get_int("--seed", 1, 0, 2000000000));
    const double laying = parse_laying(a, preset.laying());
    const double waviness = parse_perturbation(a, preset.perturbation());
    const bool json_out = a.has("--json"), quiet = a.has("--quiet") || json_out;
    estimate::FoldBranch branch = estimate::FoldBranch::Random;
    try {
        branch = estimate::parse_fold_branch(a.get_or("--branch", "random"));
        if (branch == estimate::FoldBranch::Mixed) throw ParameterError("branch: 'mixed' is a fit's choice; compare drapes random or measured");
    } catch (const Error& e) {
        throw UsageError(std::string("--") + e.what());
    }
    cloth::ModelOptions mopt = preset.model;
    mopt.edge_contact = !a.has("--vertex-contact-only");
    cloth::single_threaded_blas();
    const estimate::NoiseModel noise;

    nlohmann::json out = nlohmann::json::array();
    bool all_converged = true;
    for (const auto& dir : a.positionals()) {
        const estimate::MeasuredDrape m = estimate::load_record(dir);
        int grid = static_cast<int>(std::lround(grid300 * m.sample_diameter / 0.30));
        if (grid % 2 == 0) ++grid;
        // The record's areal density and thickness, unless --set names them: a
        // probe of "what if the specimen were thicker" (they were silently the
        // record's before, whatever --set said).
        cloth::FabricParams p = estimate::params_for_record(*base, m);
        if (!a.get_all("--set").empty()) {
            const cloth::FabricParams asked = apply_set_flags(a, p);
            for (const cloth::Param q : {cloth::Param::AreaDensity, cloth::Param::Thickness})
                if (asked[q] != p[q] && !quiet)
                    std::fprintf(stderr, "%s: --set %s = %s instead of the record's %s\n", m.id.c_str(), std::string(cloth::spec(q).key).c_str(),
                                 format_value(asked[q]).c_str(), format_value(p[q]).c_str());
            p = asked;
        }
        const estimate::DrapeFeatures meas = estimate::drape_features(m);
        std::vector<estimate::DrapeFeatures> fs;
        const int folds = branch == estimate::FoldBranch::Measured ? estimate::measured_fold_branch(meas.node_count) : 0;
        for (int s = 0; s < seeds; ++s) {
            cloth::DrapeSetup setup = m.setup(grid, seed0 + static_cast<std::uint64_t>(s));
            setup.mesh = mesh;
            if (folds > 0) setup = cloth::on_fold_branch(setup, folds);
            else {
                setup.laying_load = laying; // laid as the lab lays it
                setup.perturbation = waviness;
            }
            setup.disc_grip = a.has("--disc-grip");
            cloth::RestOptions ro;
            if (!quiet) std::fprintf(stderr, "%s: seed %d/%d (grid %d)...\n", m.id.c_str(), s + 1, seeds, grid);
            const cloth::DrapeResult r = cloth::simulate_drape(p, setup, ro, mopt);
            all_converged = all_converged && r.status.converged();
            if (!check_drape_result(r, setup)) {
                std::fprintf(stderr, "%s: seed %d of %d: nothing compared\n", m.id.c_str(), s + 1, seeds);
                return 4;
            }
            fs.push_back(estimate::drape_features(r, m));
        }
        std::vector<double> closed;
        const estimate::DrapeFeatures sim = estimate::average_features(fs, &closed);
        const auto terms = estimate::residual_terms(0, meas, sim, closed, noise);
        const double chi2 = estimate::chi_square(terms);
        check_finite(m.id, terms, chi2);
        nlohmann::json rec = comparison_json(m.id, grid, mesh, seeds, folds, chi2, terms, meas, sim, closed);
        const estimate::FreeStripCheck strips = estimate::free_strip_check(m, meas.drape_coefficient_percent, p);
        auto finite_or_null = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
        rec["free_strip"] = {{"bending_bound_Nm", finite_or_null(strips.bound_Nm)},
                             {"preset_drape_coefficient_percent", finite_or_null(strips.preset_dc_percent)},
                             {"below", strips.below}};
        out.push_back(rec);
        if (!json_out) print_comparison(rec, terms);
    }
    if (json_out) std::cout << dump_json(out) << "\n";
    return all_converged ? 0 : 4;
}

} // namespace cmd_compare

DRAPE_COMMAND({"compare", "simulate a preset on records' set-ups and compare channel by channel (no fitting)", cmd_compare::kUsage, cmd_compare::run});

} // namespace drape::cli
