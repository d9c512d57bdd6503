// drape fit: fit a fabric preset to drape-test records.
#include "cli/command.hpp"
#include "cli/progress.hpp"
#include "cli/setup.hpp"

#include "engine/core/error.hpp"
#include "engine/core/io.hpp"
#include "engine/core/text.hpp"
#include "engine/core/units.hpp"
#include "engine/fabric/preset.hpp"
#include "engine/estimate/fit.hpp"
#include "engine/estimate/measured.hpp"
#include "engine/estimate/objective.hpp"
#include "engine/estimate/report.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <iostream>

namespace drape::cli {
namespace cmd_fit {

const char* kUsage = R"(usage: drape fit RECORD_DIR [RECORD_DIR ...] --out FABRIC.json [options]

Fits one fabric preset to one or more drape-test records of the same fabric
(repeats, other sample/disc sizes): simulates the drapemeter (grid 41),
compares drape coefficient, node count, hem and the laser contours' phase-free
Fourier features with the measurement (each divided by its noise), minimises by
Levenberg-Marquardt on the exact sensitivities of the rest states (or NLopt's
CRS2 and BOBYQA), estimates 95 % intervals from the Jacobian at the optimum and
tests a library of candidate effects against the residual. Dampers are reported
as not identifiable.

  --out FILE          fitted preset (drapekit-fabric JSON with provenance, intervals, residual)
  --report DIR        write the report folder (PNG plots, report.json, report.md)
  --json              print a JSON summary (preset, intervals, records, residual) on stdout
  --model M           baseline (seed paper: bending warp/weft + shear, frictionless disc; default)
                      | stiffening (+ stiffening bending, bend_stiffening_radius_m)
                      | softening (+ yielding bending, bend_softening_radius_m)
                      | full (stiffening + tensile stiffness warp/weft)
                      | buckling (+ the membrane's compression limit, buckling_length_m)
                      | peaking (+ bending whose moment peaks at a radius and falls beyond, bend_peak_radius_m)
                      | slack (+ slack in compression, compression_slack)
  --recentre-contours measurement model: re-centre every contour stack (record and simulation)
                      on its own axis, for a profiler or specimen off the pedestal axis
  --untilt-contours   measurement model: as --recentre-contours with an axis that moves with depth
                      (offset + depth x tilt, fitted to the cuts' centroids), for a tilted profiler
                      or a drape that leans (residual candidate profiler_tilt)
  --vertex-contact-only  contact at mesh vertices only (the seed's; coarse elements then cut the
                      pedestal rim): reproduces fits made before edge contact
  --plain-bending     the grid's plain bending stencils (fits made before 2026-11-30). By
                      default the stencils carry their fourth-order correction (a fold crest one
                      cell in radius keeps its bending energy) and the preset says
                      model.bending_correction (docs/decisions/0011-bending-correction.md);
                      --bending-correction (the default) is still accepted
  --arc-membrane      the grid's springs measure the arc of their material line, not its chord
                      (a fold crest no longer reads as compression); the preset then says
                      model.arc_membrane. Off by default: docs/decisions/0019-drapemeter-mesh.md
  --channels LIST     fitted channels, any of dc,nodes,hem,contours (default all); the others
                      are held out: predicted and reported, not fitted
  --grid N            nodes across the specimen in the fit's simulations (default 41: 7.5 mm
                      between nodes on a 300 mm specimen, where presets carry over to finer meshes)
  --mesh M            the specimen's mesh in the fit's simulations: grid (default) | rings
                      (refined at the pedestal's rim; the preset's provenance.mesh, which
                      drape predict then uses)
  --refine-grid N     when the optimum is grid-bound (a fitted bending length below the mesh
                      spacing), fit again on grid N from it (default 41 when --grid is below 41,
                      else 0 = never)
  --seed K            optimizer and perturbation seed (default 1; same seed = same fit)
  --seeds S           perturbation seeds averaged per evaluation (default 2)
  --method M          lm (default): Levenberg-Marquardt on the exact sensitivities of the rest
                      states; nlopt: the derivative-free search (CRS2 global, BOBYQA local)
  --global N          global-stage (CRS2) evaluations (default: 4 per fitted parameter with
                      --method nlopt, none with lm)
  --local N           local-stage evaluations (default: lm 4 per fitted parameter + 6,
                      nlopt 8 per fitted parameter + 8)
  --branch B          where cold drapes start: measured (default; on the record's measured fold
                      count, an n-fold lift of the flat sheet), random (the seeded mix of modes, as
                      the preset drapes from flat) or mixed (even seeds measured, odd seeds random)
  --laying F          how the records' lab laid its specimens: the drapes from flat (the report's
                      "from flat", records without a node count, every drape with --branch random,
                      the odd seeds with mixed) first rest under the fraction F
                      of gravity, then under all of it (default 0.4: the drape lab's, chosen
                      leave-one-out on its set-a records; 1 = the whole load at once). Written
                      into the preset (provenance.laying_load): drape simulate and predict lay it so
  --perturbation L    how wavy the records' lab's specimens lie when laid: the largest lift of the
                      seeded waviness the same drapes from flat start from (default 6mm: the drape
                      lab's, chosen leave-one-out on its set-a records; at most 50mm; the engine's
                      own default, a preset without it, is 1mm). Written into the preset
                      (provenance.perturbation_m): drape simulate, predict, compare and the widget
                      start it so
  --flat-grid N       the fitted preset also draped from flat on grid N (the first seed; a CAD's
                      finer mesh), reported beside the fit's own grid as cold_fine_* (default 61;
                      0 or a grid not above --grid: not run)
  --flat-calibration on|off
                      on (default): when the preset draped from flat (the report's "from flat"
                      drapes, both grids) lays the record's fold count within 1 but misses its D
                      by more than the D channel's sigma, both bendings are scaled by one factor
                      (their ratio kept) until those drapes give the record's D (within that
                      sigma, at most two steps, each checked by drapes); when it lays a count
                      more than 1 off, the bendings step along the contours' profile (the other
                      fitted parameters following; 1 then 2 sigma) and the step is kept if its
                      drapes lay the count within 1 and gain more than the contours lose; the
                      report shows the contours' optimum, what moved and the chi2 it costs.
                      off: the preset is the contours' optimum
  --prior on|off      on (default): priors from 251 real fabrics (Feng et al. 2022) in the objective:
                      log10 of the warp/weft bending ratio ~ N(0, 0.3) and log10 of the mean bending
                      ~ N(-5.0, 0.6) [N*m]; the report says which the prior, not the data, decided
                      (fit.priors). A ratio beyond 3 is kept only when records of two set-ups confirm it
  --bending T         warp and weft bending: auto (default; fitted apart, and fitted again as one
                      bending when their ratio is beyond 3 but the data do not separate them - the
                      tied preset is kept unless chi2 rises by more than 9, the 3-sigma level), free (apart,
                      no test) or tied (one bending for both: an isotropic fabric)
  --shear S           in-plane shear: auto (default; fitted, and held at the typical value with
                      the rest refitted when the data leave it open-ended - its 95 % interval runs
                      into a fit bound, or it sits at one; the held preset is kept unless chi2
                      rises by more than 9)
                      or free (fitted, whatever the data say); --method nlopt fits it free
  --typical-shear G   the value auto holds the shear at [N/m] (default 56.2: KES 1 gf/(cm*deg),
                      the middle of woven apparel fabrics' range; a measured KES shear rigidity
                      in gf/(cm*deg) times 56.2), 1..1000
  --cold-global       global stage from flat starts (default: from the best point's rest
                      states, faster, but each seed keeps its fold pattern)
  --cold-local        local stage from flat starts too (every simulation is a fresh drop,
                      as the lab's and `drape predict`'s; slower)
  --start FABRIC      start point / values of the parameters not fitted (a library preset;
                      default: the table's defaults with buckling_length_m = 7.5 mm, the starters'
                      documented typical compression limit)
  --set KEY=VALUE     hold a parameter the model does not fit at VALUE (a key of the parameter
                      table in its unit, e.g. --set buckling_length_m=0.005; a fitted one starts there;
                      over --start; repeatable)
  --name NAME         name of the preset (default: the first record's id)
  --no-uncertainty    skip the Jacobian (no intervals)
  --quiet             no progress bar on stderr
Ctrl-C stops the fit and keeps the best point so far (marked cancelled).)";

std::atomic<bool> g_cancel{false};
extern "C" void on_sigint(int) { g_cancel.store(true); }

std::string join(const std::vector<std::string>& v)
{
    std::string out;
    for (const auto& s : v) out += (out.empty() ? "" : ",") + s;
    return out;
}

/// Residual terms of a record's own measurement in the fitted channels (a
/// measured value to match; NaN = not measured).
int fitted_terms(const estimate::MeasuredDrape& m, const std::vector<std::string>& channels)
{
    const estimate::DrapeFeatures f = estimate::drape_features(m);
    const std::vector<double> closed(f.contours.size(), 1.0);
    int n = 0;
    for (const auto& t : estimate::residual_terms(0, f, f, closed, estimate::NoiseModel{}))
        if (std::isfinite(t.measured) && std::find(channels.begin(), channels.end(), estimate::channel_of(t.kind)) != channels.end())
            ++n;
    return n;
}

/// A measured value for a table, "  -" where the record has none.
std::string measured_text(double v, const char* fmt)
{
    if (!std::isfinite(v)) return "    -";
    char buf[32];
    std::snprintf(buf, sizeof buf, fmt, v);
    return buf;
}

/// The fit's options from the flags, on drape fit's defaults.
estimate::FitOptions fit_options(const Args& a)
{
    estimate::FitOptions fo = estimate::drape_fit_defaults(); // every flag below falls back to it
    try {
        fo.model = estimate::parse_model_variant(a.get_or("--model", "baseline"));
    } catch (const Error& e) {
        throw UsageError(std::string("--") + e.what());
    }
    try {
        fo.method = estimate::parse_fit_method(a.get_or("--method", "lm"));
    } catch (const Error& e) {
        throw UsageError(std::string("--") + e.what());
    }
    try {
        if (const auto ch = a.get("--channels")) fo.channels = estimate::parse_channels(*ch);
    } catch (const Error& e) {
        throw UsageError(std::string("--") + e.what());
    }
    fo.grid = a.get_int("--grid", fo.grid, 9, 200);
    fo.mesh = parse_mesh(a, fo.mesh);
    fo.refine_grid = a.get_int("--refine-grid", fo.grid < 41 ? 41 : 0, 0, 200);
    if (fo.refine_grid != 0 && fo.refine_grid <= fo.grid)
        throw UsageError("--refine-grid " + std::to_string(fo.refine_grid) + " must be above --grid " + std::to_string(fo.grid) + " (or 0)");
    fo.flat_check_grid = a.get_int("--flat-grid", fo.flat_check_grid, 0, 200);
    fo.flat_calibration = a.get_on_off("--flat-calibration", fo.flat_calibration);
    fo.priors = a.get_on_off("--prior", fo.priors);
    fo.seed = static_cast<std::uint64_t>(a.get_int("--seed", 1, 0, 2000000000));
    fo.seeds_per_evaluation = a.get_int("--seeds", 2, 1, 16);
    fo.laying_load = parse_laying(a, fo.laying_load);
    fo.perturbation_m = parse_perturbation(a, fo.perturbation_m);
    fo.global_evaluations = a.get_int("--global", 0, 0, 100000);
    fo.local_evaluations = a.get_int("--local", 0, 0, 100000);
    fo.uncertainty = !a.has("--no-uncertainty");
    fo.warm_global = !a.has("--cold-global");
    try {
        if (const auto b = a.get("--branch")) fo.branch = estimate::parse_fold_branch(*b);
        if (const auto b = a.get("--bending")) fo.bending = estimate::parse_bending_tie(*b);
        if (const auto b = a.get("--shear")) fo.shear = estimate::parse_shear_hold(*b);
        fo.typical_shear_N_m = a.get_double_in("--typical-shear", fo.typical_shear_N_m, 1.0, 1000.0);
    } catch (const Error& e) {
        throw UsageError(std::string("--") + e.what());
    }
    fo.warm_local = !a.has("--cold-local");
    fo.recentre_contours = a.has("--recentre-contours");
    fo.untilt_contours = a.has("--untilt-contours");
    if (fo.recentre_contours && fo.untilt_contours)
        throw UsageError("--recentre-contours and --untilt-contours are two measurement models of the profiler's axis: choose one");
    fo.model_options.edge_contact = !a.has("--vertex-contact-only");
    // The corrected stencils by default: with them the fitted presets carry over
    // between meshes and drape from flat closer to their records (docs/decisions/0011-bending-correction.md).
    if (a.has("--bending-correction") && a.has("--plain-bending"))
        throw UsageError("--bending-correction and --plain-bending: choose one");
    if (a.has("--plain-bending")) fo.model_options.bending_correction = false;
    // Chords by default: with arcs alone the coarse grid's bending deficit at the
    // rim shows (docs/decisions/0019-drapemeter-mesh.md).
    fo.model_options.arc_membrane = a.has("--arc-membrane");
    if (fo.model_options.arc_membrane && fo.mesh != cloth::DrapeMesh::Grid)
        throw UsageError("--arc-membrane is the grid's springs; --mesh rings has the triangle model's fibre membrane");
    if (const auto s = a.get("--start")) {
        const fabric::FabricPreset start = fabric::load_fabric(*s);
        fo.start = start.params; // a seed-19 preset starts from its continuum equivalent
    }
    for (const auto& kv : a.get_all("--set"))
        for (const char* declared : {"areal_density_kg_m2=", "thickness_m="})
            if (kv.rfind(declared, 0) == 0)
                throw UsageError("--set " + kv + ": the record declares it (meta.json 'fabric'); a fit takes the lab's value");
    // Without --start the fit holds the membrane's compression limit at the
    // documented typical value (estimate::default_fit_start), not the seed's 0.
    if (!a.get_all("--set").empty()) fo.start = apply_set_flags(a, *fo.start);
    if (const auto n = a.get("--name"); n && !try_normalize_name(*n))
        throw UsageError("--name: '" + printable(*n) + "' is not a name (1..200 characters of UTF-8 text, no control characters)");
    return fo;
}

/// The records named on the command line, each with something to fit in the
/// fitted channels.
std::vector<estimate::MeasuredDrape> fit_records(const Args& a, const estimate::FitOptions& fo)
{
    std::vector<estimate::MeasuredDrape> recs;
    for (const auto& dir : a.positionals()) recs.push_back(estimate::load_record(dir));
    // Every record must give the fit something to match in a fitted channel;
    // one that gives nothing would be "fitted" to nothing.
    for (const auto& m : recs)
        if (fitted_terms(m, fo.channels) == 0)
            throw ParameterError(m.id + ": no measured value in the fitted channels (" + join(fo.channels) +
                                 "): nothing to fit it to (add the record's photos or contours, or fit other --channels)");
    return recs;
}

/// drape fit --json: the preset's parameters, fit and residual.
void print_fit_json(const Args& a, const estimate::FitOptions& fo, const estimate::FitResult& r, const nlohmann::json& preset, const std::string& out)
{
    nlohmann::json j;
    j["preset_path"] = out;
    j["name"] = r.name;
    j["model"] = estimate::to_string(fo.model);
    j["parameters"] = preset["parameters"];
    j["fit"] = preset["fit"];
    j["residual"] = preset["residual"];
    if (const auto rep = a.get("--report")) j["report_dir"] = *rep;
    std::cout << dump_json(j) << "\n";
}

/// drape fit's summary for a person: the parameters, each record, the residual
/// and what the fit's policies did.
void print_fit_text(const Args& a, const estimate::FitResult& r, const std::vector<std::string>& files, const std::string& out)
{
    std::printf("%s", estimate::parameter_table_markdown(r).c_str());
    std::printf("\n");
    for (const auto& rf : r.records) {
        const bool has_dc = std::isfinite(rf.measured_features.drape_coefficient_percent);
        const bool has_nodes = rf.measured_features.node_count >= 0;
        std::printf("%-10s D measured %s %%  fitted %5.1f %%  (error %s)   nodes measured %s  fitted %4.1f  (error %s)\n",
                    rf.measured.id.c_str(), measured_text(rf.measured_features.drape_coefficient_percent, "%5.1f").c_str(),
                    rf.simulated_features.drape_coefficient_percent,
                    measured_text(has_dc ? rf.dc_error_percent : NAN, "%+5.1f").c_str(),
                    measured_text(has_nodes ? rf.measured_features.node_count : NAN, "%2.0f").c_str(),
                    rf.simulated_features.node_count, measured_text(has_nodes ? rf.node_error : NAN, "%+4.1f").c_str());
    }
    for (const auto& rf : r.records)
        if (rf.cold_seeds > 0) {
            const bool has_dc = std::isfinite(rf.measured_features.drape_coefficient_percent);
            const bool has_nodes = rf.measured_features.node_count >= 0;
            std::printf("%-10s draped from flat (%d seeds): D %5.1f %% (error %s)   nodes %4.1f (error %s)\n", rf.measured.id.c_str(),
                        rf.cold_seeds, rf.cold_features.drape_coefficient_percent,
                        measured_text(has_dc ? rf.cold_dc_error_percent : NAN, "%+5.1f").c_str(), rf.cold_features.node_count,
                        measured_text(has_nodes ? rf.cold_node_error : NAN, "%+4.1f").c_str());
            if (rf.cold_fine_grid > 0)
                std::printf("%-10s draped from flat on grid %d: D %5.1f %% (error %s)   nodes %4.0f (error %s)%s\n", rf.measured.id.c_str(),
                            rf.cold_fine_grid, rf.cold_fine_features.drape_coefficient_percent,
                            measured_text(has_dc ? rf.cold_fine_dc_error_percent : NAN, "%+5.1f").c_str(), rf.cold_fine_features.node_count,
                            measured_text(has_nodes ? rf.cold_fine_node_error : NAN, "%+4.0f").c_str(),
                            rf.cold_fine_converged ? "" : "   NOT AT REST (the solver's iteration limit)");
        }
    std::printf("\nchi2 %.1f for %d degrees of freedom; residual %s the measurement noise (contour RMS %.2f mm)\n", r.chi2, r.dof,
                r.residual.exceeds_noise ? "EXCEEDS" : "is within", r.residual.rms_m * 1e3);
    if (r.residual.held_out_terms > 0)
        std::printf("held-out channels: %d terms, whitened RMS %.2f (fitted terms %.2f)\n", r.residual.held_out_terms,
                    r.residual.held_out_rms_whitened, r.residual.fitted_rms_whitened);
    for (const auto& b : r.residual.exceeds_because) std::printf("  beyond noise by %s\n", b.c_str());
    for (std::size_t i = 0; i < r.residual.candidate_effects.size(); ++i)
        std::printf("  candidate effect: %s (%s)\n", r.residual.candidate_effects[i].c_str(), r.residual.evidence[i].c_str());
    for (const auto& c : r.residual.candidates)
        if (c.verdict == "beyond noise")
            std::printf("  effect test: %s beyond noise (z %.1f, delta chi2 %.1f for %d parameter(s), amplitude %.3g %s)\n", c.name.c_str(), c.z,
                        c.delta_chi2, c.parameters, c.amplitude, c.amplitude_unit.c_str());
    if (!r.residual.named_effect.empty()) std::printf("named effect: %s (refit with it explains the residual)\n", r.residual.named_effect.c_str());
    else if (!r.residual.unexplained.empty()) std::printf("%s\n", r.residual.unexplained.c_str());
    if (r.refinement.from_grid > 0) std::printf("grid refinement: %s\n", r.refinement.reason.c_str());
    if (r.anisotropy.assessed && !r.anisotropy.reason.empty()) std::printf("bending: %s\n", r.anisotropy.reason.c_str());
    if (r.shear_hold.assessed && !r.shear_hold.reason.empty()) std::printf("shear: %s\n", r.shear_hold.reason.c_str());
    if (r.flat_calibration.tried) std::printf("from flat: %s\n", r.flat_calibration.reason.c_str());
    if (r.grid_bound)
        std::printf("WARNING: grid-bound preset: a fitted bending length is below the mesh spacing of grid %d; "
                    "fit with a finer --grid for a preset that carries over to other grids\n",
                    r.options.grid);
    std::printf("%d evaluations, %ld simulations (final grid %d), %.2f s per simulation, %.1f s in all%s\n", r.evaluations,
                r.simulations, r.options.grid, r.seconds_per_simulation(), r.wall_seconds,
                r.cancelled ? " (CANCELLED: best point so far)" : "");
    std::printf("preset written to %s\n", out.c_str());
    if (!files.empty()) std::printf("report: %zu files in %s\n", files.size(), a.get("--report")->c_str());
}

int run(const std::vector<std::string>& argv)
{
    Args a(argv, {"--out", "--report", "--model", "--grid", "--set", "--seed", "--seeds", "--global", "--local", "--start", "--name", "--channels", "--branch", "--refine-grid", "--method", "--bending", "--shear", "--typical-shear", "--laying", "--flat-grid", "--mesh", "--flat-calibration", "--perturbation", "--prior"},
           {"--json", "--quiet", "--no-uncertainty", "--recentre-contours", "--untilt-contours", "--vertex-contact-only", "--cold-global", "--cold-local",
            "--bending-correction", "--plain-bending", "--arc-membrane"});
    if (a.positionals().empty()) throw UsageError("at least one RECORD_DIR is required");
    reject_duplicate_records(a.positionals()); // the same record twice would count twice
    const auto out = a.get("--out");
    if (!out) throw UsageError("--out FABRIC.json is required");
    // Fail now, not after minutes of fitting.
    prepare_output_file(*out, "--out");
    if (const auto rep = a.get("--report")) prepare_output_dir(*rep, "--report");
    estimate::FitOptions fo = fit_options(a);
    const bool json = a.has("--json"), quiet = a.has("--quiet") || json;
    const std::vector<estimate::MeasuredDrape> recs = fit_records(a, fo);
    Progress progress("fit", quiet);
    if (!quiet)
        fo.progress = [&progress](const estimate::FitProgress& p) {
            if (p.stage_id == estimate::Stage::Done) return; // progress.finish below says it, with the total time
            // No percentage and no time left: the search's evaluations are bounded
            // above (`planned`) but usually far fewer, and the drapes after it (from
            // flat, the effect tests, the calibration) took as long as the search on
            // set-a - a fraction of evaluations read 16 % with "about 4 min left" a
            // second before a 49 s fit ended. The stage and the work done instead.
            progress.update(-1.0, estimate::fit_progress_line(p), p.starting);
        };
    g_cancel = false;
    fo.cancel = &g_cancel;
    auto old = std::signal(SIGINT, on_sigint);
    estimate::FitResult r = estimate::fit_fabric(recs, fo);
    std::signal(SIGINT, old);
    progress.finish(r.cancelled ? "cancelled" : "done", false); // no percentage: the fit's bar has none
    // A result that cannot be right is not written as if it were fitted.
    if (r.evaluations == 0 || r.records.empty()) {
        if (r.cancelled) {
            std::fprintf(stderr, "fit cancelled before its first evaluation; nothing written\n");
            return 3;
        }
        throw Error("the fit made no evaluation (" + std::to_string(r.records.size()) + " records): nothing written to " + *out);
    }
    if (!std::isfinite(r.chi2))
        throw Error("the fit's objective is not finite (chi2 = " + format_value(r.chi2) + "): nothing written to " + *out);
    r.params.validate("the fitted preset");
    r.name = a.get_or("--name", recs.front().id);
    nlohmann::json preset = estimate::fit_to_json(r);
    drape::write_file_atomic(*out, dump_json(preset) + "\n");
    std::vector<std::string> files;
    if (const auto rep = a.get("--report")) files = estimate::write_fit_report(r, *rep, *out);
    if (json) print_fit_json(a, fo, r, preset, *out);
    else print_fit_text(a, r, files, *out);
    return r.cancelled ? 3 : 0;
}

} // namespace cmd_fit

DRAPE_COMMAND({"fit", "fit a fabric preset to drape-test records (NLopt, with intervals)", cmd_fit::kUsage, cmd_fit::run});

} // namespace drape::cli
