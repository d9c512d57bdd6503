#include "fabric_io.hpp"

#include "error.hpp"
#include "units.hpp"

#include <cstdio>
#include <fstream>
#include <sstream>

#include <fcntl.h>
#include <unistd.h>

namespace drape::cloth {

using nlohmann::json;

std::string read_file(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    if (!in) throw FileError(path + ": cannot open file for reading");
    std::ostringstream ss;
    ss << in.rdbuf();
    if (in.bad()) throw FileError(path + ": read error");
    return ss.str();
}

void write_file_atomic(const std::string& path, const std::string& content)
{
    const std::string tmp = path + ".tmp-" + std::to_string(::getpid());
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd < 0) throw FileError(path + ": cannot create temporary file " + tmp);
    std::size_t done = 0;
    while (done < content.size()) {
        const ssize_t w = ::write(fd, content.data() + done, content.size() - done);
        if (w <= 0) {
            ::close(fd);
            ::unlink(tmp.c_str());
            throw FileError(path + ": write failed (disk full?); the previous file is unchanged");
        }
        done += static_cast<std::size_t>(w);
    }
    if (::fsync(fd) != 0 || ::close(fd) != 0) {
        ::unlink(tmp.c_str());
        throw FileError(path + ": could not flush to disk; the previous file is unchanged");
    }
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
        ::unlink(tmp.c_str());
        throw FileError(path + ": could not replace the file");
    }
}

namespace {

double number_field(const json& j, const std::string& key, const std::string& where, const std::string& prefix = "")
{
    const auto it = j.find(key);
    if (it == j.end()) throw ParameterError(where + ": missing field '" + prefix + key + "'");
    if (!it->is_number()) throw ParameterError(where + ": field '" + prefix + key + "' = " + it->dump() + " is not a number");
    return it->get<double>();
}

int int_field(const json& j, const std::string& key, const std::string& where)
{
    const double v = number_field(j, key, where);
    if (v != static_cast<double>(static_cast<long>(v)) || v < -1e9 || v > 1e9)
        throw ParameterError(where + ": field '" + key + "' = " + format_double(v) + " is not an integer");
    return static_cast<int>(v);
}

std::string bending_name(BendingModel b)
{
    switch (b) {
    case BendingModel::Quadratic: return "quadratic";
    case BendingModel::Flexion: return "flexion";
    case BendingModel::Both: return "both";
    }
    return "quadratic";
}

const char* const kSeedKeys[] = {"w", "h", "u", "v", "x0", "y0", "z0", "ClothOverMass", "SstKu", "SstDu", "SstKv",
                                 "SstDv", "SshK", "SshD", "SflKu", "SflDu", "SflKv", "SflDv"};

} // namespace

json seed_to_json(const SeedParams& s)
{
    json j;
    j["format"] = "seed-19";
    j["w"] = s.w;
    j["h"] = s.h;
    j["u"] = s.u;
    j["v"] = s.v;
    j["x0"] = s.x0;
    j["y0"] = s.y0;
    j["z0"] = s.z0;
    j["ClothOverMass"] = s.cloth_over_mass;
    j["SstKu"] = s.sst_ku;
    j["SstDu"] = s.sst_du;
    j["SstKv"] = s.sst_kv;
    j["SstDv"] = s.sst_dv;
    j["SshK"] = s.ssh_k;
    j["SshD"] = s.ssh_d;
    j["SflKu"] = s.sfl_ku;
    j["SflDu"] = s.sfl_du;
    j["SflKv"] = s.sfl_kv;
    j["SflDv"] = s.sfl_dv;
    return j;
}

SeedParams seed_from_json(const json& j, const std::string& where)
{
    if (!j.is_object()) throw ParameterError(where + ": a seed-19 preset must be a JSON object");
    SeedParams s;
    s.w = number_field(j, "w", where);
    s.h = number_field(j, "h", where);
    s.u = int_field(j, "u", where);
    s.v = int_field(j, "v", where);
    s.x0 = number_field(j, "x0", where);
    s.y0 = number_field(j, "y0", where);
    s.z0 = number_field(j, "z0", where);
    s.cloth_over_mass = number_field(j, "ClothOverMass", where);
    s.sst_ku = number_field(j, "SstKu", where);
    s.sst_du = number_field(j, "SstDu", where);
    s.sst_kv = number_field(j, "SstKv", where);
    s.sst_dv = number_field(j, "SstDv", where);
    s.ssh_k = number_field(j, "SshK", where);
    s.ssh_d = number_field(j, "SshD", where);
    s.sfl_ku = number_field(j, "SflKu", where);
    s.sfl_du = number_field(j, "SflDu", where);
    s.sfl_kv = number_field(j, "SflKv", where);
    s.sfl_dv = number_field(j, "SflDv", where);
    s.validate(where);
    return s;
}

FabricPreset fabric_from_json(const json& j, const std::string& where)
{
    if (!j.is_object()) throw ParameterError(where + ": a fabric preset must be a JSON object");
    FabricPreset out;
    const std::string format = j.contains("format") && j["format"].is_string() ? j["format"].get<std::string>() : "";
    if (format == "seed-19") {
        out.fabric = seed_from_json(j, where);
        out.model.bending = BendingModel::Flexion;
        for (const auto& [k, v] : j.items()) {
            bool known = k == "format";
            for (const char* sk : kSeedKeys) known |= k == sk;
            if (!known) out.extra[k] = v;
        }
        return out;
    }
    if (format != "drapekit-fabric")
        throw ParameterError(where + ": field 'format' = " + (j.contains("format") ? j["format"].dump() : std::string("(missing)")) +
                             " must be \"drapekit-fabric\" or \"seed-19\"");
    if (j.contains("version") && (!j["version"].is_number_integer() || j["version"].get<int>() != 1))
        throw ParameterError(where + ": field 'version' = " + j["version"].dump() + " is not supported (this build reads version 1)");
    FabricParams p;
    if (j.contains("name")) {
        if (!j["name"].is_string()) throw ParameterError(where + ": field 'name' = " + j["name"].dump() + " is not a string");
        p.name = j["name"].get<std::string>();
    }
    if (!j.contains("parameters") || !j["parameters"].is_object())
        throw ParameterError(where + ": missing object field 'parameters'");
    for (const auto& [k, v] : j["parameters"].items()) {
        const ParamSpec* sp = find_param(k);
        if (!sp) throw ParameterError(where + ": unknown parameter 'parameters." + k + "'");
        if (!v.is_number()) throw ParameterError(where + ": field 'parameters." + k + "' = " + v.dump() + " is not a number");
        p[sp->id] = v.get<double>();
    }
    p.validate(where);
    out.fabric = p;
    if (j.contains("model")) {
        const auto& m = j["model"];
        if (!m.is_object()) throw ParameterError(where + ": field 'model' must be an object");
        if (m.contains("bending")) {
            const std::string b = m["bending"].is_string() ? m["bending"].get<std::string>() : m["bending"].dump();
            if (b == "quadratic") out.model.bending = BendingModel::Quadratic;
            else throw ParameterError(where + ": field 'model.bending' = \"" + b + "\" must be \"quadratic\" for continuum presets");
        }
        if (m.contains("edge_contact")) {
            if (!m["edge_contact"].is_boolean())
                throw ParameterError(where + ": field 'model.edge_contact' = " + m["edge_contact"].dump() + " must be true or false");
            out.model.edge_contact = m["edge_contact"].get<bool>();
        }
        if (m.contains("contact_depth_m")) {
            out.model.contact_depth = number_field(m, "contact_depth_m", where, "model.");
            if (!(out.model.contact_depth > 0)) throw ParameterError(where + ": field 'model.contact_depth_m' must be positive");
        }
    }
    for (const auto& [k, v] : j.items())
        if (k != "format" && k != "version" && k != "name" && k != "parameters" && k != "model") out.extra[k] = v;
    return out;
}

json fabric_to_json(const FabricPreset& preset)
{
    json j;
    if (const auto* s = std::get_if<SeedParams>(&preset.fabric)) {
        j = seed_to_json(*s);
    } else {
        const auto& p = std::get<FabricParams>(preset.fabric);
        j["format"] = "drapekit-fabric";
        j["version"] = 1;
        j["name"] = p.name;
        json params = json::object();
        for (const auto& sp : param_table()) params[std::string(sp.key)] = p[sp.id];
        j["parameters"] = params;
        j["model"] = {{"bending", bending_name(preset.model.bending)},
                      {"contact_depth_m", preset.model.contact_depth},
                      {"edge_contact", preset.model.edge_contact}};
    }
    for (const auto& [k, v] : preset.extra.items())
        if (!j.contains(k)) j[k] = v;
    return j;
}

FabricPreset load_fabric(const std::string& path_or_name)
{
    if (path_or_name == "seed-table1") {
        FabricPreset p;
        p.fabric = SeedParams::table1();
        p.model.bending = BendingModel::Flexion;
        p.extra["name"] = "seed-table1";
        p.extra["source"] = "Kuzmina, Tamas, Halasz, Grof: Image-based cloth capture and cloth simulation used for "
                            "estimation cloth draping parameters, Table 1 (start run of the simulator)";
        return p;
    }
    const std::string text = read_file(path_or_name);
    json j;
    try {
        j = json::parse(text);
    } catch (const json::parse_error& e) {
        throw FileError(path_or_name + ": not valid JSON (" + e.what() + ")");
    }
    return fabric_from_json(j, path_or_name);
}

void save_fabric(const FabricPreset& p, const std::string& path) { write_file_atomic(path, fabric_to_json(p).dump(2) + "\n"); }

} // namespace drape::cloth
