#include "engine/fabric/preset.hpp"

#include "engine/core/error.hpp"
#include "engine/core/io.hpp"
#include "engine/core/json_reader.hpp"
#include "engine/core/units.hpp"

#include <cmath>

namespace drape::fabric {

using nlohmann::json;

cloth::Material FabricPreset::material() const
{
    if (seed) return cloth::Material(params, grid_springs(*seed));
    return cloth::Material(params);
}

void FabricPreset::set_params(const cloth::FabricParams& p)
{
    params = p;
    if (seed) {
        seed.reset();
        model = cloth::ModelOptions{};
    }
}

namespace {

std::string bending_name(cloth::BendingModel b)
{
    switch (b) {
    case cloth::BendingModel::Quadratic: return "quadratic";
    case cloth::BendingModel::Flexion: return "flexion";
    case cloth::BendingModel::Both: return "both";
    }
    return "quadratic";
}

/// Keys a typed field owns; everything else goes to `extra`.
bool is_typed_key(const std::string& k)
{
    for (const char* t : {"format", "version", "name", "parameters", "model", "composition", "source", "notes",
                          "provenance", "fit", "drape_coefficient"})
        if (k == t) return true;
    return false;
}

std::string optional_string(const JsonReader& r, const json& j, const std::string& key)
{
    return JsonReader::find(j, key) ? r.string(j, key) : std::string();
}

Provenance read_provenance(const JsonReader& r, const json& root)
{
    const json& j = r.need(root, "provenance");
    if (!j.is_object()) r.fail("provenance", "must be an object, got " + describe_json(j));
    Provenance p;
    p.details = j;
    // "tool" since `drape fit` wrote it, "kind" in the starter files.
    if (j.contains("tool") && j["tool"].is_string()) p.tool = j["tool"].get<std::string>();
    else if (j.contains("kind") && j["kind"].is_string()) p.tool = j["kind"].get<std::string>();
    for (const char* k : {"date_utc", "date"})
        if (j.contains(k) && j[k].is_string()) {
            p.date = j[k].get<std::string>();
            break;
        }
    if (j.contains("grid")) p.grid = r.integer(root, "provenance.grid", 5, 1000);
    if (j.contains("laying_load")) p.laying_load = r.number_in(root, "provenance.laying_load", 1e-3, 1.0);
    if (j.contains("perturbation_m")) p.perturbation_m = r.number_in(root, "provenance.perturbation_m", 0.0, 0.05);
    if (j.contains("records") && j["records"].is_array())
        for (const auto& rec : j["records"]) {
            if (rec.is_string()) p.records.push_back(rec.get<std::string>());
            else if (rec.is_object() && rec.contains("id") && rec["id"].is_string()) p.records.push_back(rec["id"].get<std::string>());
        }
    return p;
}

json write_provenance(const Provenance& p)
{
    json j = p.details.is_object() ? p.details : json::object();
    if (!p.tool.empty()) j[j.contains("kind") && !j.contains("tool") ? "kind" : "tool"] = p.tool;
    if (!p.date.empty()) j[j.contains("date") && !j.contains("date_utc") ? "date" : "date_utc"] = p.date;
    if (p.grid > 0) j["grid"] = p.grid;
    if (p.laying_load > 0) j["laying_load"] = p.laying_load;
    else j.erase("laying_load"); // not stated: laid at once
    if (p.perturbation_m) j["perturbation_m"] = *p.perturbation_m;
    else j.erase("perturbation_m"); // not stated: the engine's default
    if (!j.contains("records") && !p.records.empty()) j["records"] = p.records;
    return j;
}

FitSummary read_fit(const JsonReader& r, const json& root)
{
    const json& j = r.need(root, "fit");
    if (!j.is_object()) r.fail("fit", "must be an object, got " + describe_json(j));
    FitSummary f;
    f.details = j;
    if (j.contains("chi2")) f.chi2 = r.number_in(root, "fit.chi2", 0, 1e300);
    if (j.contains("dof")) f.dof = r.integer(root, "fit.dof", 0, 100000000);
    if (j.contains("reduced_chi2")) f.reduced_chi2 = r.number_in(root, "fit.reduced_chi2", 0, 1e300);
    else if (j.contains("quality")) f.reduced_chi2 = r.number_in(root, "fit.quality", 0, 1e300); // before typed presets
    else if (f.dof > 0) f.reduced_chi2 = f.chi2 / f.dof;
    if (j.contains("grid_bound")) f.grid_bound = r.boolean(root, "fit.grid_bound");
    if (j.contains("records") && !j["records"].is_array()) r.fail("fit.records", "must be an array, got " + describe_json(j["records"]));
    if (j.contains("records") && !j["records"].empty() && j["records"][0].is_object()) {
        // The set-up of the first record: `drape predict` scales its grid by it,
        // so a value of another type is an error, not "unknown" (a string
        // "0.15" made predict drape at half the fit's mesh density).
        const json& first = j["records"][0];
        for (auto [key, out] : {std::pair{"sample_diameter_m", &f.sample_diameter_m}, {"disc_diameter_m", &f.disc_diameter_m}})
            if (first.contains(key)) {
                if (!first[key].is_number())
                    r.fail(std::string("fit.records[0].") + key, "must be a number [m], got " + describe_json(first[key]));
                const double d = first[key].get<double>();
                if (!(d > 0 && d <= 5))
                    r.fail(std::string("fit.records[0].") + key, "= " + format_value(d) + " m is outside (0, 5] m");
                *out = d;
            }
    }
    return f;
}

json write_fit(const FitSummary& f)
{
    json j = f.details.is_object() ? f.details : json::object();
    j["chi2"] = f.chi2;
    j["dof"] = f.dof;
    if (f.reduced_chi2) j["reduced_chi2"] = *f.reduced_chi2;
    j["grid_bound"] = f.grid_bound;
    j.erase("quality");
    return j;
}

DrapeReference read_drape(const JsonReader& r, const json& root)
{
    const json& j = r.need(root, "drape_coefficient");
    DrapeReference d;
    if (j.is_number()) {
        // Before the percent rule: a bare fraction 0..1.
        d.percent = 100.0 * r.number_in(root, "drape_coefficient", 0, 1);
        return d;
    }
    if (!j.is_object()) r.fail("drape_coefficient", "must be an object, got " + describe_json(j));
    d.details = j;
    if (j.contains("percent")) d.percent = r.number_in(root, "drape_coefficient.percent", 0, 100, "%");
    else if (j.contains("value")) d.percent = 100.0 * r.number_in(root, "drape_coefficient.value", 0, 1); // fraction, before the percent rule
    else r.fail("drape_coefficient.percent", "is missing");
    if (j.contains("kind")) d.kind = r.string(root, "drape_coefficient.kind");
    if (j.contains("sample_diameter_m")) d.sample_diameter_m = r.number_in(root, "drape_coefficient.sample_diameter_m", 0, 5, "m");
    if (j.contains("disc_diameter_m")) d.disc_diameter_m = r.number_in(root, "drape_coefficient.disc_diameter_m", 0, 5, "m");
    if (j.contains("method")) d.method = r.string(root, "drape_coefficient.method");
    for (const char* k : {"date", "simulated_on"})
        if (j.contains(k) && j[k].is_string()) {
            d.date = j[k].get<std::string>();
            break;
        }
    return d;
}

json write_drape(const DrapeReference& d)
{
    json j = d.details.is_object() ? d.details : json::object();
    j.erase("value");
    j.erase("simulated_on");
    j["percent"] = d.percent;
    j["kind"] = d.kind;
    if (d.sample_diameter_m > 0) j["sample_diameter_m"] = d.sample_diameter_m;
    if (d.disc_diameter_m > 0) j["disc_diameter_m"] = d.disc_diameter_m;
    if (!d.method.empty()) j["method"] = d.method;
    if (!d.date.empty()) j["date"] = d.date;
    return j;
}

void read_descriptions(const JsonReader& r, const json& j, FabricPreset& out)
{
    if (j.contains("name")) out.name = r.string(j, "name");
    out.composition = optional_string(r, j, "composition");
    out.source = optional_string(r, j, "source");
    out.notes = optional_string(r, j, "notes");
    if (j.contains("provenance")) out.provenance = read_provenance(r, j);
    if (j.contains("fit")) out.fit = read_fit(r, j);
    if (j.contains("drape_coefficient")) out.drape = read_drape(r, j);
}

} // namespace

FabricPreset fabric_from_json(const json& j, const std::string& where)
{
    if (!j.is_object()) throw ParameterError(where + ": a fabric preset must be a JSON object");
    const JsonReader r(where);
    FabricPreset out;
    const std::string format = j.contains("format") && j["format"].is_string() ? j["format"].get<std::string>() : "";
    if (format == "seed-19") {
        out.seed = seed_from_json(j, where);
        out.params = continuum_from_seed(*out.seed);
        out.model.bending = cloth::BendingModel::Flexion;
        out.name = "seed-19";
        read_descriptions(r, j, out);
        for (const auto& [k, v] : j.items())
            if (!is_seed_key(k) && !is_typed_key(k)) out.extra[k] = v;
        return out;
    }
    if (format != "drapekit-fabric")
        throw ParameterError(where + ": field 'format' = " + (j.contains("format") ? describe_json(j["format"]) : std::string("(missing)")) +
                             " must be \"drapekit-fabric\" or \"seed-19\"");
    if (j.contains("version") && (!j["version"].is_number_integer() || j["version"].get<int>() != 1))
        throw ParameterError(where + ": field 'version' = " + describe_json(j["version"]) + " is not supported (this build reads version 1)");
    read_descriptions(r, j, out);
    if (!j.contains("parameters") || !j["parameters"].is_object())
        throw ParameterError(where + ": missing object field 'parameters'");
    for (const auto& [k, v] : j["parameters"].items()) {
        const cloth::ParamSpec* sp = cloth::find_param(k);
        if (!sp) throw ParameterError(where + ": unknown parameter 'parameters." + k + "'");
        if (!v.is_number()) throw ParameterError(where + ": field 'parameters." + k + "' = " + describe_json(v) + " is not a number");
        const double x = v.get<double>();
        if (!(x >= sp->lower && x <= sp->upper)) // named as the file writes it (a key before the unit-suffix rule too)
            throw ParameterError(where + ": field 'parameters." + k + "' = " + format_value(x) + " " + std::string(sp->unit) +
                                 " is outside [" + format_value(sp->lower) + ", " + format_value(sp->upper) + "]");
        out.params[sp->id] = x;
    }
    out.params.validate(where);
    if (j.contains("model")) {
        const auto& m = j["model"];
        if (!m.is_object()) throw ParameterError(where + ": field 'model' must be an object");
        if (m.contains("bending")) {
            const std::string b = m["bending"].is_string() ? m["bending"].get<std::string>() : describe_json(m["bending"]);
            if (b == "quadratic") out.model.bending = cloth::BendingModel::Quadratic;
            else throw ParameterError(where + ": field 'model.bending' = \"" + b + "\" must be \"quadratic\" for continuum presets");
        }
        // A switch of the model: absent keeps the default (bending_correction and
        // arc_membrane are absent in presets written before they existed: off, as made).
        auto read_switch = [&](const char* key, bool& to) {
            if (!m.contains(key)) return;
            if (!m[key].is_boolean())
                throw ParameterError(where + ": field 'model." + key + "' = " + describe_json(m[key]) + " must be true or false");
            to = m[key].get<bool>();
        };
        read_switch("edge_contact", out.model.edge_contact);
        // "buckling": "euler" was the first buckling model (2026-11-29), the Euler
        // load of a strip as long as the mesh spacing; it is read as the material
        // length it had on the default grid (60 nodes on 300 mm: 5 mm) unless the
        // preset gives buckling_length_m. "none": the linear membrane.
        if (m.contains("buckling")) {
            const std::string b = m["buckling"].is_string() ? m["buckling"].get<std::string>() : m["buckling"].dump();
            if (b == "euler") {
                if (!j["parameters"].contains("buckling_length_m")) out.params[cloth::Param::BucklingLength] = 0.005;
            } else if (b != "none")
                throw ParameterError(where + ": field 'model.buckling' = \"" + b + "\" must be \"euler\" or \"none\"");
        }
        read_switch("bending_correction", out.model.bending_correction); // since 2026-11-30
        read_switch("arc_membrane", out.model.arc_membrane);             // since 2026-12-01
        if (m.contains("contact_depth_m")) {
            if (!m["contact_depth_m"].is_number() || !(m["contact_depth_m"].get<double>() > 0) ||
                !(m["contact_depth_m"].get<double>() < 0.01))
                throw ParameterError(where + ": field 'model.contact_depth_m' = " + describe_json(m["contact_depth_m"]) +
                                     " must be a length in (0, 0.01) m");
            out.model.contact_depth = m["contact_depth_m"].get<double>();
        }
    }
    for (const auto& [k, v] : j.items())
        if (!is_typed_key(k)) out.extra[k] = v;
    return out;
}

json fabric_to_json(const FabricPreset& preset)
{
    json j;
    if (preset.seed) {
        j = seed_to_json(*preset.seed);
        j["name"] = preset.name;
    } else {
        j["format"] = "drapekit-fabric";
        j["version"] = 1;
        j["name"] = preset.name;
        json params = json::object();
        for (const auto& sp : cloth::param_table()) params[std::string(sp.key)] = preset.params[sp.id];
        j["parameters"] = params;
        j["model"] = {{"bending", bending_name(preset.model.bending)},
                      {"contact_depth_m", preset.model.contact_depth},
                      {"edge_contact", preset.model.edge_contact},
                      {"bending_correction", preset.model.bending_correction},
                      {"arc_membrane", preset.model.arc_membrane}};
    }
    if (!preset.composition.empty()) j["composition"] = preset.composition;
    if (!preset.source.empty()) j["source"] = preset.source;
    if (!preset.notes.empty()) j["notes"] = preset.notes;
    if (preset.drape) j["drape_coefficient"] = write_drape(*preset.drape);
    if (preset.provenance) j["provenance"] = write_provenance(*preset.provenance);
    if (preset.fit) j["fit"] = write_fit(*preset.fit);
    for (const auto& [k, v] : preset.extra.items())
        if (!j.contains(k)) j[k] = v;
    return j;
}

std::optional<FabricPreset> builtin_fabric(const std::string& name)
{
    if (name != "seed-table1") return std::nullopt;
    FabricPreset p;
    p.seed = SeedParams::table1();
    p.params = continuum_from_seed(*p.seed);
    p.model.bending = cloth::BendingModel::Flexion;
    p.name = "seed-table1";
    p.source = "Kuzmina, Tamas, Halasz, Grof: Image-based cloth capture and cloth simulation used for "
               "estimation cloth draping parameters, Table 1 (start run of the simulator)";
    return p;
}

FabricPreset load_fabric(const std::string& path_or_name)
{
    if (auto b = builtin_fabric(path_or_name)) return *b;
    return fabric_from_json(read_json_file(path_or_name), path_or_name);
}

void save_fabric(const FabricPreset& p, const std::string& path) { write_file_atomic(path, fabric_to_json(p).dump(2) + "\n"); }

} // namespace drape::fabric
