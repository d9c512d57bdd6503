// `drape import FILE`: what a mesh file holds once it is in the engine's frame.
#include <stdexcept> // before command.hpp, which uses std::runtime_error

#include "cli/command.hpp"

#ifdef HAVE_DRAPE_IMPORTERS
#include "engine/core/error.hpp"
#include "engine/core/units.hpp"
#include "importers/mesh_import.hpp"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <iostream>

namespace cmd_import {

using namespace drape;

nlohmann::json vec(const Eigen::Vector3d& v) { return nlohmann::json::array({v.x(), v.y(), v.z()}); }

nlohmann::json box_json(const importers::AlignedBox& b)
{
    return {{"min", vec(b.min)}, {"max", vec(b.max)}, {"size", vec(b.size())}};
}

int run_import(const std::vector<std::string>& argv)
{
    cli::Args args(argv, {"--unit", "--up"}, {"--json"});
    if (args.positionals().size() != 1) throw cli::UsageError("import needs exactly one FILE");
    importers::ImportOptions opt;
    try {
        opt.unit = importers::parse_unit(args.get_or("--unit", "file"), "--unit");
        opt.up = importers::parse_up_axis(args.get_or("--up", "file"), "--up");
    } catch (const drape::Error& e) {
        throw cli::UsageError(e.what());
    }
    const std::string& path = args.positionals().front();
    const importers::ImportedScene scene = importers::import_scene(path, opt);
    const importers::AlignedBox box = scene.bounds();

    if (args.has("--json")) {
        nlohmann::json j;
        j["file"] = path;
        j["format"] = scene.format;
        j["unit_scale_m"] = scene.unit_scale;
        j["unit_source"] = scene.unit_source;
        j["up_axis"] = importers::to_string(scene.up);
        j["up_source"] = scene.up_source;
        j["vertices"] = scene.vertex_count();
        j["triangles"] = scene.triangle_count();
        j["bounding_box_m"] = box_json(box);
        j["meshes"] = nlohmann::json::array();
        for (const auto& m : scene.meshes)
            j["meshes"].push_back({{"name", m.name},
                                   {"vertices", m.vertex_count()},
                                   {"triangles", m.triangle_count()},
                                   {"bounding_box_m", box_json(m.bounds())}});
        std::cout << cli::dump_json(j) << "\n";
        return 0;
    }
    std::printf("%s  (%s)\n", path.c_str(), scene.format.c_str());
    std::printf("unit: %g m per file unit (%s); up axis: %s (%s); engine frame: metres, z up\n", scene.unit_scale,
                scene.unit_source.c_str(), importers::to_string(scene.up).c_str(), scene.up_source.c_str());
    std::printf("%-32s %10s %10s   %s\n", "mesh", "vertices", "triangles", "bounding box [m] (min .. max)");
    for (const auto& m : scene.meshes) {
        const auto b = m.bounds();
        std::printf("%-32s %10d %10d   (%.4f, %.4f, %.4f) .. (%.4f, %.4f, %.4f)\n", m.name.c_str(), m.vertex_count(),
                    m.triangle_count(), b.min.x(), b.min.y(), b.min.z(), b.max.x(), b.max.y(), b.max.z());
    }
    std::printf("%-32s %10d %10d   (%.4f, %.4f, %.4f) .. (%.4f, %.4f, %.4f)\n", "total", scene.vertex_count(),
                scene.triangle_count(), box.min.x(), box.min.y(), box.min.z(), box.max.x(), box.max.y(), box.max.z());
    std::printf("size [m]: %.4f x %.4f x %.4f\n", box.size().x(), box.size().y(), box.size().z());
    if (scene.unit_source == "assumed" || scene.up_source == "assumed")
        std::printf("note: the file declares no %s; pass --unit/--up if the assumption is wrong\n",
                    scene.unit_source == "assumed" && scene.up_source == "assumed" ? "unit or up axis"
                    : scene.unit_source == "assumed"                              ? "unit"
                                                                                  : "up axis");
    return 0;
}

DRAPE_COMMAND({"import", "report the meshes of a mesh file (assimp) in metres, z up",
               "usage: drape import FILE [--unit mm|cm|m] [--up y|z] [--json]\n"
               "  Reads FILE through assimp (OBJ, Collada/ZAE, glTF/GLB, FBX, PLY, STL, ...), applies the\n"
               "  scene's node transforms, converts to the engine's frame (metres, z up) and prints each\n"
               "  mesh's name, vertex and triangle counts and bounding box in metres.\n"
               "  --unit   unit of the numbers in the file (default: what the file declares, else metres)\n"
               "  --up     the file's up axis (default: what the file declares, else y)\n"
               "  --json   machine-readable: vertices, triangles, bounding_box_m {min, max}, meshes[]",
               run_import});

} // namespace cmd_import
#endif
