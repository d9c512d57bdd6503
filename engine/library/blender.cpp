#include "engine/library/blender.hpp"

#include "engine/cloth/params.hpp"
#include "engine/core/error.hpp"

#include <algorithm>
#include <cstdio>
#include <string>

namespace drape::library {

namespace {

/// Blender's cloth solver scales gravity by this (SIM_mass_spring.cc,
/// cloth_calc_force: "mul_v3_v3fl(gravity, scene->physics_settings.gravity,
/// 0.001f * ...)"), so stiffnesses are scaled alike.
constexpr double kBlenderGravityScale = 0.001;
/// Blender's angular bending spring: k = bending * restlen * 0.1.
constexpr double kBlenderBendScale = 0.1;

std::string num(double v)
{
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.9g", v);
    return buf;
}

std::string py_string(const std::string& s)
{
    std::string out = "\"";
    for (char c : s) {
        if (c == '\\' || c == '"') out += '\\';
        if (c == '\n') {
            out += "\\n";
            continue;
        }
        out += c;
    }
    return out + "\"";
}

} // namespace

BlenderCloth blender_cloth(const fabric::FabricPreset& preset, double h)
{
    if (!(h > 0)) throw ParameterError("Blender export: edge length " + num(h) + " m must be positive");
    const cloth::FabricParams& v = preset.params;
    using cloth::Param;
    const double stretch = 0.5 * (v[Param::StretchWarp] + v[Param::StretchWeft]);
    const double bend = 0.5 * (v[Param::BendWarp] + v[Param::BendWeft]);
    BlenderCloth b;
    b.edge_m = h;
    b.vertex_mass_kg = v[Param::AreaDensity] * h * h;
    // Structural spring k = tension / h (Blender), k = stretch (a grid line of a
    // continuum sheet: force Y h dL/h per strip of width h): tension = g' Y h.
    b.tension = kBlenderGravityScale * stretch * h;
    b.compression = b.tension;
    // Quad diagonals under a shear strain g stretch by +-h g / sqrt(2): two of
    // them store 1/2 k h^2 g^2 per cell, the continuum 1/2 G g^2 h^2: k = G.
    b.shear = kBlenderGravityScale * v[Param::Shear] * h;
    // Angular spring: force 0.1 bending l (theta - theta0) on the far side of a
    // face, a moment 0.1 bending l theta h about the hinge; the continuum strip:
    // B l kappa with kappa = theta / h. Equal (gravity scaled): bending = 0.01 B / h^2.
    b.bending = kBlenderGravityScale * bend / (kBlenderBendScale * h * h);
    b.collision_distance_m = std::max(0.5 * v[Param::Thickness], 0.001);
    return b;
}

std::string preset_to_blender_script(const fabric::FabricPreset& preset)
{
    const cloth::FabricParams& v = preset.params;
    using cloth::Param;
    std::string s;
    s += "# Drapekit fabric " + py_string(preset.name) + " as Blender cloth settings.\n";
    s += "# Written by `drape library export NAME --format blender`. Select the garment (a mesh object,\n";
    s += "# quads preferred) and run this script in Blender's Text Editor (Run Script), or\n";
    s += "#   blender scene.blend --python this_file.py\n";
    s += "# It adds or updates the object's Cloth modifier from the fabric's SI parameters and the\n";
    s += "# object's own mesh (mean edge length h, area, vertex count): Blender's cloth stiffnesses\n";
    s += "# depend on the edge length. The mapping and its derivation: Drapekit docs/library.md, \"Blender\".\n";
    s += "#\n";
    s += "# For settings typed by hand, on a regular quad mesh of edge h:\n";
    s += "#   h [mm]   vertex mass [kg]   tension = compression   shear        bending (angular)\n";
    for (double h : {0.005, 0.01, 0.02}) {
        const BlenderCloth b = blender_cloth(preset, h);
        char line[200];
        std::snprintf(line, sizeof line, "#   %-6.0f   %-16.4g   %-21.4g   %-10.4g   %.4g\n", h * 1e3, b.vertex_mass_kg, b.tension,
                      b.shear, b.bending);
        s += line;
    }
    s += "#   collision distance " + num(blender_cloth(preset, 0.01).collision_distance_m) + " m\n\n";
    s += "import math\n\nimport bpy\n\n";
    s += "FABRIC = {\n";
    s += "    \"name\": " + py_string(preset.name) + ",\n";
    s += "    \"composition\": " + py_string(preset.composition) + ",\n";
    for (const cloth::ParamSpec& p : cloth::param_table())
        s += "    \"" + std::string(p.key) + "\": " + num(v[p.id]) + ",  # " + std::string(p.unit) + "\n";
    s += "}\n\n";
    s += R"(GRAVITY_SCALE = 0.001  # Blender's cloth solver scales gravity by 0.001 (SIM_mass_spring.cc)
BEND_SCALE = 0.1  # Blender's angular bending spring: k = bending * edge length * 0.1


def mesh_measures(obj):
    """Mean edge length [m], area [m^2] and vertex count of the object's mesh in world space."""
    mw = obj.matrix_world
    verts = [mw @ v.co for v in obj.data.vertices]
    edges = obj.data.edges
    if not edges:
        raise RuntimeError("the object has no edges")
    h = sum((verts[e.vertices[0]] - verts[e.vertices[1]]).length for e in edges) / len(edges)
    area = 0.0
    for poly in obj.data.polygons:
        ids = list(poly.vertices)
        for k in range(1, len(ids) - 1):
            a, b, c = verts[ids[0]], verts[ids[k]], verts[ids[k + 1]]
            area += 0.5 * (b - a).cross(c - a).length
    return h, area, len(verts)


def apply(obj=None):
    obj = obj or bpy.context.active_object
    if obj is None or obj.type != 'MESH':
        raise RuntimeError("select the garment: a mesh object")
    h, area, n = mesh_measures(obj)
    f = FABRIC
    stretch = 0.5 * (f["stretch_warp_N_m"] + f["stretch_weft_N_m"])
    bend = 0.5 * (f["bend_warp_Nm"] + f["bend_weft_Nm"])
    mod = next((m for m in obj.modifiers if m.type == 'CLOTH'), None) or obj.modifiers.new("Cloth", 'CLOTH')
    s = mod.settings
    s.mass = f["areal_density_kg_m2"] * area / n
    s.tension_stiffness = GRAVITY_SCALE * stretch * h
    s.compression_stiffness = s.tension_stiffness
    s.shear_stiffness = GRAVITY_SCALE * f["shear_N_m"] * h
    s.bending_model = 'ANGULAR'
    s.bending_stiffness = GRAVITY_SCALE * bend / (BEND_SCALE * h * h)
    mod.collision_settings.distance_min = max(0.5 * f["thickness_m"], 0.001)
    print("Drapekit fabric %s on %s: h = %.4g m, vertex mass %.4g kg, tension %.4g, shear %.4g, bending %.4g"
          % (f["name"], obj.name, h, s.mass, s.tension_stiffness, s.shear_stiffness, s.bending_stiffness))
    return mod


if __name__ == "__main__":
    apply()
)";
    return s;
}

} // namespace drape::library
