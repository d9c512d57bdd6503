// drape simulate: drape a fabric preset over the drapemeter and measure it.
#include "cli/command.hpp"
#include "cli/checks.hpp"
#include "cli/progress.hpp"
#include "cli/setup.hpp"
#include "engine/core/units.hpp"

#include "engine/cloth/blas_threads.hpp"
#include "engine/cloth/drape_io.hpp"
#include "engine/cloth/rest_sensitivity.hpp"
#include "engine/cloth/self_intersection.hpp"
#include "engine/core/error.hpp"
#include "engine/core/io.hpp"
#include "engine/core/text.hpp"
#include "engine/fabric/preset.hpp"
#ifdef HAVE_DRAPE_CAPTURE
#include "engine/capture/mesh_picture.hpp"
#endif

#include <cmath>
#include <cstdio>
#include <iostream>

#include <nlohmann/json.hpp>

namespace drape::cli {
namespace cmd_simulate {

const char* kUsage = R"(usage: drape simulate --fabric FABRIC.json|seed-table1 [options]

Drapes a round specimen over the drapemeter pedestal to rest and measures it
(drape coefficient, nodes, hem height, slices).

  --fabric F            preset file (drapekit-fabric or seed-19 JSON), seed-table1, a fabric of the
                        library, or a starter fabric: silk, cotton, wool, denim
  --set KEY=VALUE       override one parameter of the preset (a key of the parameter table in its
                        unit, e.g. --set bend_warp_Nm=2e-6; repeatable)
  --sample-diameter L   specimen diameter (default 300mm; units mm, cm, m; bare = m)
  --disc-diameter L     pedestal disc diameter (default 150mm)
  --pedestal-height L   pedestal height (default 120mm)
  --edge-radius L       rounding of the pedestal top edge (default 0.5mm)
  --grid N              nodes across the specimen (default 60; a seed-19 preset drapes on its own grid,
                        u + 1 nodes across, and refuses another)
  --mesh M              the specimen's mesh: grid (default: the square lattice) | rings
                        (concentric rings refined to 0.4 of the spacing at the pedestal's rim, where
                        the cloth bends over it; docs/model-discrepancy.md section 25)
  --integrator I        static (default) | implicit | rk4 | midpoint | symplectic | euler
  --dt S                time step [s] (default: chosen per integrator)
  --tolerance R         relative force residual at rest (default 1e-6)
  --max-time S          give up after S seconds of simulated time (dynamic; default 60)
  --max-iterations N    static solver: Newton iterations per level (default 1000)
  --seed K              perturbation seed (default 1)
  --folds N             start on an N-fold branch (an N-fold lift of 5 mm, N in 2..16; default: the
                        seeded mix of modes 2..16, 1 mm)
  --fold-angle DEG      with --folds: one crest of the lift this far from the warp (+x) towards the
                        weft (default: a seeded angle); the folds rest near it
  --laying F            how the specimen is laid: it first rests under the fraction F of gravity, then
                        under all of it (default: the preset's provenance.laying_load, what its fit
                        assumed of its records' lab - drape fit: 0.4 -, else 1 = the whole load at
                        once; 1 with --folds unless --laying is given). Static solver only: the
                        dynamic integrators fall under the whole load
  --perturbation L      largest lift of the flat start's perturbation (default: the preset's
                        provenance.perturbation_m, how wavy its lab laid it; else 1mm; at most 50mm)
  --out DIR             write summary.json, rest.obj, slices.csv, outline.csv and rest.png (the rest
                        state seen from the front and from above)
  --json                print the summary as JSON on stdout
  --quiet               no progress on stderr (a terminal gets one line with percent and time left,
                        a log or pipe plain lines)
  --disc-grip           the specimen cannot slide on the disc top (large static friction)
  --vertex-contact-only contact at mesh vertices only (the seed's): coarse elements cut the pedestal rim
  --bending-correction  the grid's bending stencils with their fourth-order correction (a fold crest one
                        cell in radius keeps its bending energy; docs/model-discrepancy.md sections 18-19);
                        on too when the preset says model.bending_correction (the starters and the
                        fits made since 2026-11-30 do)
  --plain-bending       the plain stencils even where the preset says model.bending_correction (to
                        compare; a preset drapes as it was fitted only with its own setting)
  --arc-membrane        the grid's springs measure the arc of their material line, not its chord (a
                        fold crest no longer reads as compression; docs/model-discrepancy.md section
                        24); on too when the preset says model.arc_membrane (a fit with --arc-membrane)
  --chord-membrane      the springs measure chords even where the preset says model.arc_membrane
  --self-collision      keep the cloth from passing through itself (a barrier one fabric thickness
                        wide; off by default: a drapemeter's folds stay open). The summary counts the
                        rest state's self-intersections either way
  --trace               print every static-solver iteration on stderr
  --sensitivity KEYS    at the rest state, the exact derivative of D and of the mean hem height with
                        respect to each parameter (comma-separated keys of the parameter table, or
                        all): dx/dp = H^-1 df/dp, one factorisation, no further drapes (static solver))";

/// --sensitivity KEY,...|all: the parameters whose exact sensitivities of D and
/// the hem the command prints.
std::vector<cloth::Param> sensitivity_params(const Args& a, const fabric::FabricPreset& preset, const cloth::RestOptions& ro)
{
    std::vector<cloth::Param> sens_params;
    if (const auto keys = a.get("--sensitivity")) {
        if (ro.integrator != cloth::Integrator::Static) throw UsageError("--sensitivity needs the static solver (a rest state)");
        if (preset.seed) throw UsageError("--sensitivity: a seed-19 preset's grid springs are not continuum parameters");
        for (const auto& key : split_list(*keys)) {
            if (key == "all") {
                for (const auto& sp : cloth::param_table())
                    if (sp.affects_statics && preset.params[sp.id] != 0) sens_params.push_back(sp.id);
                continue;
            }
            const cloth::ParamSpec* sp = cloth::find_param(key);
            if (!sp) throw UsageError("--sensitivity: unknown parameter '" + printable(key) + "'");
            if (!sp->affects_statics) throw UsageError("--sensitivity " + key + ": a damper does not move a rest state");
            if (preset.params[sp->id] == 0) throw UsageError("--sensitivity " + key + ": the value is 0 (set it with --set first)");
            sens_params.push_back(sp->id);
        }
        if (sens_params.empty()) throw UsageError("--sensitivity: no parameter");
    }
    return sens_params;
}

/// The model's switches from the flags (contact, self-collision, the bending
/// stencils, the membrane), refused where the preset or the mesh has no such choice.
void apply_model_flags(const Args& a, fabric::FabricPreset& preset, const cloth::DrapeSetup& setup)
{
    preset.model.edge_contact = !a.has("--vertex-contact-only");
    preset.model.self_collision = a.has("--self-collision");
    if (a.has("--bending-correction")) {
        if (preset.seed) throw UsageError("--bending-correction: a seed-19 preset has grid springs, no bending stencils to correct");
        if (a.has("--plain-bending")) throw UsageError("--bending-correction and --plain-bending: choose one");
        preset.model.bending_correction = true;
    }
    if (a.has("--plain-bending")) preset.model.bending_correction = false;
    if (a.has("--arc-membrane")) {
        if (preset.seed) throw UsageError("--arc-membrane: a seed-19 preset's grid springs are its own constants");
        if (a.has("--chord-membrane")) throw UsageError("--arc-membrane and --chord-membrane: choose one");
        if (setup.mesh != cloth::DrapeMesh::Grid)
            throw UsageError("--arc-membrane is the grid's springs; --mesh " + std::string(cloth::to_string(setup.mesh)) +
                             " has the triangle model's fibre membrane");
        preset.model.arc_membrane = true;
    }
    if (a.has("--chord-membrane")) preset.model.arc_membrane = false;
}

#ifdef HAVE_DRAPE_CAPTURE
/// A picture of the rest state for a person (OUT/rest.png): the cloth and the
/// pedestal.
void write_rest_picture(const std::string& out, const cloth::DrapeResult& r, const cloth::DrapeSetup& setup, const cloth::ClothSystem& sys,
                        const fabric::FabricPreset& preset)
{
    // The pedestal: a cylinder (top cap and side) 1 mm below the cloth it carries.
    const int seg = 64;
    const double rad = 0.5 * setup.disc_diameter, top = -1e-3, bottom = -setup.pedestal_height;
    cloth::Positions ped(2 * seg + 1, 3);
    cloth::Triangles pf(3 * seg, 3);
    for (int k = 0; k < seg; ++k) {
        const double t = 2 * M_PI * k / seg;
        ped.row(k) << rad * std::cos(t), rad * std::sin(t), top;
        ped.row(seg + k) << rad * std::cos(t), rad * std::sin(t), bottom;
    }
    ped.row(2 * seg) << 0, 0, top;
    for (int k = 0; k < seg; ++k) {
        const int k1 = (k + 1) % seg;
        pf.row(3 * k) << 2 * seg, k, k1;
        pf.row(3 * k + 1) << k, seg + k, seg + k1;
        pf.row(3 * k + 2) << k, seg + k1, k1;
    }
    char title[160];
    std::snprintf(title, sizeof title, "%s  D = %.1f %%, %d nodes (%.0f/%.0f mm, grid %d)", preset.name.c_str(),
                  r.metrics.drape_coefficient_percent, r.metrics.node_count, setup.sample_diameter * 1e3,
                  setup.disc_diameter * 1e3, setup.grid);
    capture::write_mesh_picture(out + "/rest.png",
                                {{&r.x, &sys.mesh().F, cv::Scalar(72, 58, 176)}, {&ped, &pf, cv::Scalar(150, 150, 150)}},
                                title);
}
#endif

/// The rest state for a person: D, nodes, the hem, the solver, how it was laid
/// and the sensitivities.
void print_simulation(const cloth::DrapeResult& r, const cloth::DrapeSetup& setup, const cloth::RestOptions& ro, const nlohmann::json& summary,
                      const fabric::FabricPreset& preset, const std::vector<cloth::DrapeMetricSensitivity>& sens)
{
    std::printf("drape coefficient  %.1f %%\n", r.metrics.drape_coefficient_percent);
    std::printf("nodes              %d\n", r.metrics.node_count);
    std::printf("hem height         %.1f .. %.1f mm (below the pedestal top)\n", r.hem.min_z * 1e3, r.hem.max_z * 1e3);
    std::printf("self-intersections %ld (self-collision %s)\n", summary["self_intersections"].get<long>(),
                preset.model.self_collision ? "on" : "off");
    std::printf("solver             %s: %s, %ld steps, %ld force evaluations, %.2f s\n", to_string(ro.integrator).c_str(),
                to_string(r.status.outcome).c_str(), r.status.steps, r.status.force_evaluations, r.status.wall_seconds);
    if (ro.integrator == cloth::Integrator::Static && setup.laying_load < 1)
        std::printf("laying             first at rest under %s g (the preset's lab; --laying 1: the whole load at once)\n",
                    format_value(setup.laying_load).c_str());
    if (setup.fold_mode == 0 && setup.perturbation != cloth::kStartLift)
        std::printf("start              flat, %s mm wavy at most (the preset's lab; --perturbation 1mm: the engine's default)\n",
                    format_value(setup.perturbation * 1e3).c_str());
    if (!r.status.message.empty()) std::printf("                   %s\n", r.status.message.c_str());
    if (!sens.empty()) std::printf("sensitivity        D change for +10 %% of each parameter (exact, at this rest state):\n");
    for (const auto& t : sens) {
        const auto& sp = cloth::spec(t.param);
        std::printf("  %-26s %10.4g %-7s  dD %+7.2f points   mean hem %+7.2f mm\n", std::string(sp.key).c_str(), t.value,
                    std::string(sp.unit).c_str(), t.d_drape_coefficient_percent * 0.1 * t.value, t.d_hem_mean_z * 0.1 * t.value * 1e3);
    }
}

int run(const std::vector<std::string>& argv)
{
    Args a(argv,
           fabric_flags() + setup_value_flags(kAllSetup) +
               std::set<std::string>{"--integrator", "--dt", "--tolerance", "--max-time", "--out", "--max-iterations", "--sensitivity"},
           setup_switches(kAllSetup) + std::set<std::string>{"--json", "--quiet", "--trace", "--vertex-contact-only", "--self-collision",
                                                                 "--bending-correction", "--plain-bending", "--arc-membrane", "--chord-membrane"});
    if (!a.positionals().empty()) throw UsageError("unexpected argument '" + a.positionals().front() + "'");
    fabric::FabricPreset preset = load_fabric_flags(a);
    cloth::DrapeSetup defaults;
    defaults.grid = 60;
    defaults = preset.laid(defaults); // a fitted preset is laid (and as wavy) as its records' lab laid them
    const cloth::DrapeSetup setup = on_preset_grid(a, preset, parse_setup(a, defaults));
    cloth::RestOptions ro;
    try {
        ro.integrator = cloth::parse_integrator(a.get_or("--integrator", "static"));
    } catch (const Error& e) {
        throw UsageError(std::string("--") + e.what());
    }
    ro.dt = a.get_double("--dt", 0.0);
    if (ro.dt < 0 || ro.dt > 10) throw UsageError("--dt: " + std::to_string(ro.dt) + " s is outside [0, 10]");
    ro.residual = a.get_double("--tolerance", 1e-6);
    if (!(ro.residual > 0) || ro.residual >= 1) throw UsageError("--tolerance must be in (0, 1)");
    ro.max_newton = a.get_int("--max-iterations", 1000, 1, 1000000);
    ro.max_sim_time = a.get_double("--max-time", 60.0);
    if (!(ro.max_sim_time > 0) || ro.max_sim_time > 1e5) throw UsageError("--max-time must be in (0, 1e5] s of simulated time");
    const bool json = a.has("--json"), quiet = a.has("--quiet") || json;
    const std::vector<cloth::Param> sens_params = sensitivity_params(a, preset, ro);
    ro.trace = a.has("--trace");
    apply_model_flags(a, preset, setup);
    Progress progress("simulate", quiet);
    if (!quiet) ro.progress = progress.solver_callback(ro);
    cloth::single_threaded_blas(); // the same rounding as the widget, predict and garment: the same rest state
    const cloth::DrapeResult r = cloth::simulate_drape(preset.material(), setup, ro, preset.model);
    progress.finish(to_string(r.status.outcome), r.status.converged());
    if (!check_drape_result(r, setup)) return 4;
    auto summary = cloth::drape_summary_json(r, setup, ro.integrator);
    const auto sys = cloth::make_drape_system(preset.material(), setup, preset.model); // the mesh topology
    summary["fabric_model"] = fabric_model_name(preset); // "grid" above is the mesh draped: a seed-19 preset's own
    summary["self_collision"] = preset.model.self_collision;
    // The crest correction is the grid stencils' (the ring mesh's triangle model has
    // its own exact-for-quadratics stencils): true only where it was applied.
    summary["bending_correction"] = preset.model.bending_correction && setup.mesh == cloth::DrapeMesh::Grid;
    summary["arc_membrane"] = preset.model.arc_membrane;
    summary["self_intersections"] = cloth::self_intersections(r.x, sys->mesh().F).pairs;
    std::vector<cloth::DrapeMetricSensitivity> sens;
    if (!sens_params.empty() && r.status.converged()) {
        sens = cloth::drape_metric_sensitivities(preset.material(), setup, r.x, sens_params, preset.model);
        nlohmann::json arr = nlohmann::json::array();
        for (const auto& t : sens)
            arr.push_back({{"key", std::string(cloth::spec(t.param).key)},
                           {"value", t.value},
                           {"dD_dp_percent", t.d_drape_coefficient_percent},
                           {"dD_per_10_percent_change", t.d_drape_coefficient_percent * 0.1 * t.value},
                           {"dhem_mean_dp_m", t.d_hem_mean_z},
                           {"solve_residual", t.solve_residual}});
        summary["sensitivities"] = arr;
    }
    if (const auto out = a.get("--out")) {
        cloth::write_drape_outputs(*out, r, setup, ro.integrator, sys->mesh());
        // The summary as printed (with the self-intersection count and any sensitivities).
        write_file_atomic(*out + "/summary.json", summary.dump(2) + "\n");
#ifdef HAVE_DRAPE_CAPTURE
        write_rest_picture(*out, r, setup, *sys, preset);
#endif
    }
    if (json) std::cout << dump_json(summary) << "\n";
    else print_simulation(r, setup, ro, summary, preset, sens);
    if (r.status.outcome == cloth::SolverStatus::Outcome::NotConverged && ro.integrator == cloth::Integrator::Static)
        std::fprintf(stderr, "drape simulate: not at rest within %ld Newton iterations per level (exit 4; the metrics are the last state's): "
                             "--max-iterations %ld to let it go on\n",
                     ro.max_newton, 3 * ro.max_newton);
    return r.status.converged() ? 0 : 4;
}

} // namespace cmd_simulate

DRAPE_COMMAND({"simulate", "drape a fabric preset over the drapemeter and measure it", cmd_simulate::kUsage, cmd_simulate::run});

} // namespace drape::cli
