#include "engine/library/u3m.hpp"
#include "engine/core/clock.hpp"

#include "engine/cloth/params.hpp"
#include "engine/core/error.hpp"
#include "engine/core/json_reader.hpp"
#include "engine/core/text.hpp"
#include "engine/core/units.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <ctime>
#include <regex>

namespace drape::library {

namespace {

using nlohmann::json;

constexpr const char* kBlock = "drapekit";
constexpr const char* kBlockFormat = "drapekit-u3m-physics";
constexpr int kBlockVersion = 1;

std::uint64_t fnv1a(const std::string& s, std::uint64_t h)
{
    for (unsigned char c : s) {
        h ^= c;
        h *= 1099511628211ull;
    }
    return h;
}

/// A UUID4-shaped id (version 4, variant 1, as the schema's pattern requires)
/// derived from the name, so a re-export of the same fabric keeps its id.
std::string uuid_from_name(const std::string& name)
{
    const std::uint64_t a = fnv1a("drapekit:" + name, 14695981039346656037ull);
    const std::uint64_t b = fnv1a(name + ":u3m", a ^ 0x9e3779b97f4a7c15ull);
    std::array<unsigned char, 16> u{};
    for (int i = 0; i < 8; ++i) {
        u[std::size_t(i)] = static_cast<unsigned char>(a >> (8 * i));
        u[std::size_t(8 + i)] = static_cast<unsigned char>(b >> (8 * i));
    }
    u[6] = static_cast<unsigned char>((u[6] & 0x0f) | 0x40);
    u[8] = static_cast<unsigned char>((u[8] & 0x3f) | 0x80);
    char buf[40];
    std::snprintf(buf, sizeof buf, "%02x%02x%02x%02x-%02x%02x-%02x%02x-%02x%02x-%02x%02x%02x%02x%02x%02x", u[0], u[1], u[2],
                  u[3], u[4], u[5], u[6], u[7], u[8], u[9], u[10], u[11], u[12], u[13], u[14], u[15]);
    return buf;
}

/// The fibre names of U3M 1.1's composition_part.type (u3m_schema.json).
const char* const kFibres[] = {
    "Abaca", "Acetate", "Acrylic", "Alfa", "Alginate", "Alpaca", "Aluminium", "Angora", "Aramid", "Beaver",
    "Camelhair", "Cashmere", "Cotton", "Cupro", "Elastane", "Guanaco", "Hardware", "Hemp", "Jute", "Linen",
    "Llama", "Lycra", "Lyocell", "Meril", "Metallic Fibre", "Metallised Polyester", "Micropolypch", "Modacrylic",
    "Modal Cotton", "Modal", "Mohair", "Neoprene", "Nylon", "Organic cotton", "Polyacryl", "Polyamid", "Polyester",
    "Polyethylene", "Polypropylen", "Polytaslan", "Ramie", "Rayon", "Recycled Cotton", "Recycled Polyamide",
    "Recycled Polyester", "Silk", "Spandex", "Tactel", "Triacetate", "Vicugna", "Vinyl", "Virgin Wool", "Wild Silk",
    "Wool", "Yack", "Viscose"};

double number_or(const json& j, const char* key, double fallback)
{
    if (!j.is_object() || !j.contains(key) || !j[key].is_number()) return fallback;
    return j[key].get<double>();
}

} // namespace

json composition_parts(const std::string& composition)
{
    static const std::regex part(R"((\d+(?:\.\d+)?)\s*%\s*([A-Za-z][A-Za-z \-]*[A-Za-z]))");
    json parts = json::array();
    double sum = 0;
    for (auto it = std::sregex_iterator(composition.begin(), composition.end(), part); it != std::sregex_iterator(); ++it) {
        const double ratio = std::stod((*it)[1].str()) / 100.0;
        const std::string fibre = trim_blanks((*it)[2].str());
        std::string type = "other";
        for (const char* f : kFibres)
            if (ascii_lower(f) == ascii_lower(fibre)) type = f;
        if (type == "Viscose") type = "Rayon"; // not in U3M's list: the same fibre
        parts.push_back({{"ratio", ratio}, {"type", type}, {"name", type == "other" ? json(fibre) : json(nullptr)}});
        sum += ratio;
    }
    if (parts.empty() || std::abs(sum - 1.0) > 0.005) return nullptr;
    return {{"parts", parts}};
}

json preset_to_u3m(const fabric::FabricPreset& p, const U3mOptions& opt)
{
    const cloth::FabricParams& v = p.params;
    const std::string created = opt.created.empty() ? utc_now() : opt.created;
    json parameters = json::object();
    for (const cloth::ParamSpec& s : cloth::param_table())
        parameters[std::string(s.key)] = {{"value", v[s.id]}, {"unit", std::string(s.unit)}, {"doc", std::string(s.doc)}};
    json physics = {
        {"thickness", v[cloth::Param::Thickness] * 1e3},   // [mm]
        {"weight", v[cloth::Param::AreaDensity] * 1e3},    // [g/m^2]
        {"composition", composition_parts(p.composition)},
        {"devices", {{"fab", "null"}}},
        {"material_type", nullptr},
        {"construction", nullptr}};
    json block = {
        {"format", kBlockFormat},
        {"version", kBlockVersion},
        {"about", "Drapekit's continuum cloth parameters: resolution-independent SI values per unit width, warp = "
                  "the fabric's u direction, weft = v. 'parameters' holds each with its unit; 'preset' is the whole "
                  "Drapekit preset (drapekit-fabric or seed-19 JSON) for a lossless round trip. docs/library.md, "
                  "section U3M."},
        {"parameters", parameters},
        {"preset", fabric::fabric_to_json(p)}};
    return {{"schema", "1.1"},
            {"material",
             {{"id", uuid_from_name(p.name)},
              {"name", p.name.empty() ? std::string("unnamed") : p.name},
              {"description", p.notes},
              {"created", created},
              {"modified", opt.modified.empty() ? created : opt.modified},
              {"front", nullptr},
              {"back", nullptr},
              {"side", nullptr},
              {"physics", physics},
              {"metadata", nullptr}}},
            {"custom", {{kBlock, block}}}};
}

bool is_u3m(const json& j)
{
    return j.is_object() && j.contains("schema") && j["schema"].is_string() && j.contains("material") &&
           j["material"].is_object();
}

fabric::FabricPreset preset_from_u3m(const json& j, const std::string& where, std::string* note)
{
    if (!is_u3m(j)) throw ParameterError(where + ": not a U3M document (no \"schema\" and \"material\")");
    const std::string schema = j["schema"].get<std::string>();
    if (schema != "1.0" && schema != "1.1")
        throw ParameterError(where + ": field 'schema' = \"" + schema + "\": U3M 1.0 and 1.1 are read");
    const json& m = j["material"];
    if (!m.contains("name") || !m["name"].is_string() || m["name"].get<std::string>().empty())
        throw ParameterError(where + ": field 'material.name' is missing or empty");
    const std::string name = m["name"].get<std::string>();
    if (m.contains("physics") && !m["physics"].is_object() && !m["physics"].is_null())
        throw ParameterError(where + ": field 'material.physics' = " + describe_json(m["physics"]) + " must be an object");
    const json physics = m.contains("physics") && m["physics"].is_object() ? m["physics"] : json::object();
    const json custom = j.contains("custom") && j["custom"].is_object() ? j["custom"] : json::object();
    const json block = custom.contains(kBlock) && custom[kBlock].is_object() ? custom[kBlock] : json::object();

    fabric::FabricPreset p;
    std::string from;
    if (block.contains("preset") && block["preset"].is_object()) {
        p = fabric::fabric_from_json(block["preset"], where + ": custom.drapekit.preset");
        from = "the Drapekit preset block";
    } else if (block.contains("parameters") && block["parameters"].is_object()) {
        cloth::FabricParams v;
        for (const auto& [key, entry] : block["parameters"].items()) {
            const cloth::ParamSpec* s = cloth::find_param(key);
            if (!s) continue; // a newer Drapekit's parameter: the table's default stays
            if (!entry.is_object() || !entry.contains("value") || !entry["value"].is_number())
                throw ParameterError(where + ": field 'custom.drapekit.parameters." + key + ".value' is not a number");
            v[s->id] = entry["value"].get<double>();
        }
        p.set_params(v);
        p.name = name;
        from = "the Drapekit parameters block";
    } else {
        p.name = name;
        p.source = "U3M material from another tool (" + where + ")";
        from = "the parameter table's defaults (the file has no Drapekit block: stretch, shear and bending are not "
               "measured values)";
    }
    if (p.name.empty() || p.name == "unnamed") p.name = name;
    if (p.notes.empty() && m.contains("description") && m["description"].is_string()) p.notes = m["description"].get<std::string>();
    if (p.composition.empty() && physics.contains("composition") && physics["composition"].is_object() &&
        physics["composition"].contains("parts") && physics["composition"]["parts"].is_array()) {
        std::string text;
        for (std::size_t i = 0; i < physics["composition"]["parts"].size(); ++i) {
            const json& part = physics["composition"]["parts"][i];
            // A ratio that is not a number would print as "0 % cotton": refused, named.
            if (part.is_object() && part.contains("ratio") && !part["ratio"].is_number())
                throw ParameterError(where + ": field 'material.physics.composition.parts[" + std::to_string(i) + "].ratio' = " +
                                     describe_json(part["ratio"]) + " is not a number (a fraction of 1)");
            const double r = number_or(part, "ratio", 0);
            std::string fibre = part.contains("name") && part["name"].is_string() ? part["name"].get<std::string>()
                                : part.contains("type") && part["type"].is_string() ? part["type"].get<std::string>()
                                                                                     : "unknown";
            text += (text.empty() ? "" : ", ") + format_value(std::round(r * 1000) / 10) + " % " + ascii_lower(fibre);
        }
        p.composition = text;
    }

    // The U3M's own fields win where they differ from the block (another tool
    // edited the weight): U3M's rule for values held twice.
    cloth::FabricParams v = p.params;
    bool changed = false;
    std::string overridden;
    auto take = [&](const char* key, cloth::Param id, double scale, const char* unit) {
        // null: not stated (our own export writes null for what it does not know).
        if (!physics.contains(key) || physics[key].is_null()) return;
        // Anything else that is not a number ("sixty") was dropped silently: refused, named.
        if (!physics[key].is_number())
            throw ParameterError(where + ": field 'material.physics." + key + "' = " + describe_json(physics[key]) +
                                 " is not a number (in " + unit + ")");
        const double value = physics[key].get<double>() * scale;
        if (std::abs(value - v[id]) <= 1e-9 * std::max(1.0, std::abs(v[id]))) return;
        v[id] = value;
        changed = true;
        overridden += std::string(overridden.empty() ? "" : ", ") + key + " " + format_value(physics[key].get<double>()) + " " + unit;
    };
    take("weight", cloth::Param::AreaDensity, 1e-3, "g/m^2");
    take("thickness", cloth::Param::Thickness, 1e-3, "mm");
    if (changed) {
        v.validate(where + ": material.physics");
        if (p.is_seed())
            throw ParameterError(where + ": material.physics (" + overridden +
                                 ") differs from the seed-19 preset it carries; a seed preset's mass is its grid constants'");
        p.set_params(v);
    } else {
        p.params.validate(where);
    }
    if (note) {
        *note = "read " + name + " from " + from;
        if (changed) *note += "; weight/thickness from material.physics (" + overridden + ")";
    }
    return p;
}

} // namespace drape::library
