// drape garment: drape a garment on a mannequin to rest and measure it.
#include "cli/command.hpp"
#include "cli/setup.hpp"

#include "engine/capture/mesh_picture.hpp"
#include "engine/cloth/blas_threads.hpp"
#include "engine/cloth/drape_io.hpp"
#include "engine/core/error.hpp"
#include "engine/core/io.hpp"
#include "importers/garment_metrics.hpp"
#include "importers/garment_scene.hpp"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <unistd.h>

namespace drape::cli {
namespace cmd_garment {

const char* kUsage = R"(usage: drape garment --body FILE --garment circle-skirt|FILE [options]

Drapes a garment on a mannequin to rest and measures it: the hem's distance
from the body's axis and its folds, vertices inside the body, self-intersections.

  --body FILE           mannequin mesh (anything assimp reads, e.g. Debian's
                        /usr/share/assimp/models/Collada/human.zae, the MakeHuman body)
  --unit U, --up A      the body file's unit (mm, cm, m) and up axis (y, z); default: as the file says
  --garment G           circle-skirt (a circular skirt sized to the body's waist), or a garment
                        mesh FILE whose holding vertices are in a mesh/object/group named
                        "waist..." or "pin..." (OBJ: `g waist` before the waistband's faces)
  --fabric F            preset file, seed-table1, a fabric of the library, or a starter:
                        silk, cotton, wool, denim (default cotton)
  --set KEY=VALUE       override one parameter of the preset (repeatable)
  --length L            circle skirt: waistband to hem (default 500mm)
  --self-collision on|off
                        keep the cloth from passing through itself (default on: a barrier
                        holds every two parts of the cloth one fabric thickness apart)
  --out DIR             write rest.obj, summary.json and garment.png (front and top views)
  --json                print the summary as JSON on stdout
  --quiet               no progress on stderr
  --trace               print every static-solver iteration on stderr (after the skirt's fall)

Exit codes: 0 at rest, 1 bad input, 2 bad command line, 4 the solver did not reach rest.)";

int run(const std::vector<std::string>& argv)
{
    Args a(argv, fabric_flags() + std::set<std::string>{"--body", "--garment", "--unit", "--up", "--out", "--length", "--self-collision"},
           {"--json", "--quiet", "--trace"});
    if (!a.positionals().empty()) throw UsageError("unexpected argument '" + a.positionals().front() + "'");
    const auto body = a.get("--body");
    if (!body) throw UsageError("--body FILE is required (a mannequin mesh)");
    const std::string garment = a.get_or("--garment", "circle-skirt");
    const auto out = a.get("--out");
    if (out) prepare_output_dir(*out, "--out");
    importers::ImportOptions io;
    try {
        io.unit = importers::parse_unit(a.get_or("--unit", "file"), "--unit");
        io.up = importers::parse_up_axis(a.get_or("--up", "file"), "--up");
    } catch (const Error& e) {
        throw UsageError(e.what());
    }
    const bool self_collision = a.get_on_off("--self-collision", true);
    fabric::FabricPreset preset = load_fabric_flags(a, "cotton");
    const bool json = a.has("--json"), quiet = a.has("--quiet") || json;
    cloth::single_threaded_blas();

    auto mannequin = std::make_shared<importers::Mannequin>(importers::load_mannequin(*body, io));
    importers::Scene scene;
    if (garment == "circle-skirt" || garment == "skirt") {
        importers::SkirtOptions so;
        so.length = a.get_length("--length", so.length);
        if (!(so.length > 0.05 && so.length < 2.0)) throw UsageError("--length: must be in (50mm, 2m)");
        scene = importers::make_skirt_scene(mannequin, preset, so);
    } else {
        std::error_code ec;
        if (!std::filesystem::is_regular_file(garment, ec))
            throw FileError("--garment " + garment + ": not circle-skirt and not a mesh file");
        scene = importers::make_garment_scene(mannequin, garment, preset);
    }
    cloth::ClothSystem& sys = *scene.system;
    if (!self_collision) sys.model().self_contact_distance = 0;
    cloth::RestOptions ro = importers::garment_rest_options();
    ro.trace = a.has("--trace");
    const bool tty = ::isatty(STDERR_FILENO);
    if (!quiet)
        ro.progress = [tty](const cloth::SolverStatus& st) {
            std::fprintf(stderr, tty ? "\r  %-6ld iterations  residual %.2e  %.1f s   " : "  %ld iterations  residual %.2e  %.1f s\n",
                         st.newton_iterations, st.residual, st.wall_seconds);
            return true;
        };
    const cloth::SolverStatus st = importers::drape_to_rest(scene, ro);
    if (!quiet && tty) std::fprintf(stderr, "\n");
    const importers::GarmentMetrics gm =
        importers::garment_metrics(sys.x, sys.mesh().F, sys.model().pinned, mannequin.get(), scene.waist.centre);

    nlohmann::json j;
    j["converged"] = st.converged();
    j["status"] = cloth::to_string(st.outcome);
    j["message"] = st.message;
    j["residual_relative"] = st.residual;
    j["wall_seconds"] = st.wall_seconds;
    j["newton_iterations"] = st.newton_iterations;
    j["steps"] = st.steps;
    j["vertices"] = sys.vertex_count();
    j["triangles"] = static_cast<long>(sys.mesh().F.rows());
    j["fabric"] = preset.name;
    j["garment"] = scene.garment_name;
    j["body"] = *body;
    j["body_axis_m"] = {scene.waist.centre.x(), scene.waist.centre.y()};
    j["waist_height_m"] = scene.waist.z;
    j["hem_mean_radius_m"] = gm.hem_mean_radius_m;
    j["hem_min_height_m"] = gm.hem_min_z_m;
    j["hem_max_height_m"] = gm.hem_max_z_m;
    j["hem_fold_count"] = gm.hem_fold_count;
    j["vertices_inside_body"] = gm.vertices_inside_body;
    j["min_body_distance_m"] = gm.min_body_distance_m;
    j["self_intersections"] = gm.self_intersections;
    j["self_collision"] = sys.self_contact_on();
    j["self_contact_distance_m"] = sys.model().self_contact_distance;
    j["self_contact_pairs"] = static_cast<long>(sys.self_contact_pairs(sys.x).size());
    if (out) {
        namespace fs = std::filesystem;
        const fs::path dir(*out);
        cloth::write_obj((dir / "rest.obj").string(), sys.x, sys.mesh().F, &sys.mesh().uv);
        write_file_atomic((dir / "summary.json").string(), dump_json(j) + "\n");
        char title[256];
        std::snprintf(title, sizeof title, "%s, %s: hem radius %.0f mm, %d folds, %s", scene.garment_name.c_str(),
                      preset.name.c_str(), gm.hem_mean_radius_m * 1e3, gm.hem_fold_count, cloth::to_string(st.outcome).c_str());
        capture::write_mesh_picture((dir / "garment.png").string(),
                                    {{&mannequin->mesh.X, &mannequin->mesh.F, cv::Scalar(175, 175, 175)},
                                     {&sys.x, &sys.mesh().F, cv::Scalar(60, 60, 170)}},
                                    title);
    }
    if (json) {
        std::cout << dump_json(j) << "\n";
    } else {
        std::printf("garment            %s on %s\n", scene.garment_name.c_str(), body->c_str());
        std::printf("fabric             %s\n", preset.name.c_str());
        std::printf("hem                mean radius %.1f mm from the body's axis, %d folds, height %.0f .. %.0f mm\n",
                    gm.hem_mean_radius_m * 1e3, gm.hem_fold_count, gm.hem_min_z_m * 1e3, gm.hem_max_z_m * 1e3);
        std::printf("body               %d vertices inside, closest %.2f mm\n", gm.vertices_inside_body, gm.min_body_distance_m * 1e3);
        std::printf("self-intersections %ld (self-collision %s", gm.self_intersections, sys.self_contact_on() ? "on" : "off");
        if (sys.self_contact_on())
            std::printf(", %.2f mm apart, %zu pairs in contact", sys.model().self_contact_distance * 1e3, sys.self_contact_pairs(sys.x).size());
        std::printf(")\n");
        std::printf("solver             %s, %ld Newton iterations, residual %.1e, %.1f s\n", cloth::to_string(st.outcome).c_str(),
                    st.newton_iterations, st.residual, st.wall_seconds);
        if (!st.message.empty()) std::printf("                   %s\n", st.message.c_str());
        if (out) std::printf("outputs            %s/{rest.obj,summary.json,garment.png}\n", out->c_str());
    }
    return st.converged() ? 0 : 4;
}

} // namespace cmd_garment

DRAPE_COMMAND({"garment", "drape a garment on a mannequin and measure it (hem, folds, body, self-intersections)", cmd_garment::kUsage, cmd_garment::run});

} // namespace drape::cli
