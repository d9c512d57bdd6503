// `drape library ...`: manage the SQLite fabric library from scripts and shells.
#include <stdexcept> // before command.hpp, which uses std::runtime_error

#include "cli/command.hpp"

#ifdef HAVE_DRAPE_LIBRARY
#include "engine/core/error.hpp"
#include "engine/core/io.hpp"
#include "engine/core/units.hpp"
#include "engine/fabric/preset.hpp"
#include "engine/library/blender.hpp"
#include "engine/library/fabric_library.hpp"
#include "engine/library/resolve.hpp"
#include "engine/library/u3m.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>

namespace cmd_library {

using namespace drape;
using namespace drape::library;
using nlohmann::json;

json null_or(const std::optional<double>& v) { return v ? json(*v) : json(nullptr); }

json record_json(const FabricRecord& r, bool with_preset)
{
    json j = {{"name", r.name},
              {"composition", r.composition},
              {"format", r.format},
              {"areal_density_kg_m2", r.areal_density_kg_m2},
              {"drape_coefficient_percent", null_or(r.drape_coefficient_percent)},
              {"fit_quality", null_or(r.fit_quality)},
              {"created", r.created},
              {"modified", r.modified},
              {"revision", r.revision}};
    if (with_preset) j["preset"] = r.preset_json;
    return j;
}

std::string fmt_opt(const std::optional<double>& v, const char* f, double scale = 1.0)
{
    if (!v) return "-";
    char buf[64];
    std::snprintf(buf, sizeof buf, f, *v * scale);
    return buf;
}

/// D on the command line, in percent as everywhere in Drapekit: "65" or "65%".
double parse_percent(const std::string& flag, const std::string& text)
{
    std::string t = text;
    const bool sign = !t.empty() && t.back() == '%';
    if (sign) t.pop_back();
    double v = 0;
    if (!parse_number(t, v)) throw cli::UsageError(flag + ": '" + text + "' is not a percentage (e.g. 65 or 65%)");
    if (v < 0 || v > 100) throw cli::UsageError(flag + ": '" + text + "' is outside 0..100 %");
    if (!sign && v > 0 && v <= 1)
        throw cli::UsageError(flag + ": '" + text + "' reads as " + text + " % (D is in percent); write " + format_value(100 * v) +
                              " for " + format_value(100 * v) + " %, or " + text + "% if you mean it");
    return v;
}

/// A fabric name given on the command line: a usage error (exit 2) when the
/// library would refuse it, with the library's reason.
void check_name_flag(const std::string& name, const std::string& what = "--name")
{
    try {
        library::validate_name(name);
    } catch (const ParameterError& e) {
        throw cli::UsageError(what + ": " + e.what());
    }
}

OnConflict parse_conflict(const std::string& s)
{
    if (s == "fail") return OnConflict::Fail;
    if (s == "skip") return OnConflict::Skip;
    if (s == "replace") return OnConflict::Replace;
    if (s == "rename") return OnConflict::Rename;
    throw cli::UsageError("--on-conflict: '" + s + "' must be fail, skip, replace or rename");
}

void write_output(const json& j, const std::optional<std::string>& out)
{
    if (out && *out != "-") drape::write_file_atomic(*out, cli::dump_json(j) + "\n");
    else std::cout << cli::dump_json(j) << "\n";
}

const std::set<std::string> kCommon = {"--library"};
std::set<std::string> with_common(std::set<std::string> s)
{
    s.insert(kCommon.begin(), kCommon.end());
    return s;
}

/// The library the flags name (--library), or the default one.
FabricLibrary open_library_of(const cli::Args& a, FabricLibrary::Mode m)
{
    const auto path = a.get("--library");
    if (path && path->empty()) throw cli::UsageError("--library: the path is empty (leave the flag out for the default library)");
    return open_library(path.value_or(""), m);
}

/// drape library list: the fabrics a filter selects, as a table or JSON.
int library_list(const std::vector<std::string>& rest)
{
    cli::Args a(rest,
                with_common({"--name", "--composition", "--search", "--weight-min", "--weight-max", "--d-min", "--d-max",
                             "--fit-min", "--fit-max", "--since", "--until", "--sort", "--limit"}),
                {"--json", "--desc"});
    if (!a.positionals().empty()) throw cli::UsageError("library list takes no positional arguments");
    Filter f;
    f.name = a.get_or("--name", "");
    f.composition = a.get_or("--composition", "");
    f.text = a.get_or("--search", "");
    // Weights on the command line in g/m^2, the unit on fabric labels.
    if (auto s = a.get("--d-min")) f.drape_min = parse_percent("--d-min", *s);
    if (auto s = a.get("--d-max")) f.drape_max = parse_percent("--d-max", *s);
    if (a.get("--weight-min")) f.weight_min = a.get_double_in("--weight-min", 0, 0, 1e4, "g/m^2") * 1e-3;
    if (a.get("--weight-max")) f.weight_max = a.get_double_in("--weight-max", 0, 0, 1e4, "g/m^2") * 1e-3;
    if (a.get("--fit-min")) f.fit_min = a.get_double_in("--fit-min", 0, 0, 1e300);
    if (a.get("--fit-max")) f.fit_max = a.get_double_in("--fit-max", 0, 0, 1e300);
    f.modified_from = a.get_or("--since", "");
    f.modified_to = a.get_or("--until", "");
    for (const auto& [flag, date] : {std::pair{"--since", f.modified_from}, {"--until", f.modified_to}})
        if (!date.empty() && !is_iso_date(date))
            throw cli::UsageError(std::string(flag) + ": '" + date + "' is not an ISO 8601 date such as 2026-11-22 or 2026-11-22T10:30");
    const std::string sort = a.get_or("--sort", "name");
    if (sort == "name") f.sort = SortKey::Name;
    else if (sort == "weight") f.sort = SortKey::Weight;
    else if (sort == "d" || sort == "D") f.sort = SortKey::DrapeCoefficient;
    else if (sort == "modified" || sort == "date") f.sort = SortKey::Modified;
    else if (sort == "fit") f.sort = SortKey::FitQuality;
    else throw cli::UsageError("--sort: '" + sort + "' must be name, weight, d, modified or fit");
    f.descending = a.has("--desc");
    f.limit = a.get_int("--limit", 0, 0, 1000000);
    const FabricLibrary lib = open_library_of(a, FabricLibrary::Mode::ReadOnly);
    const auto rows = lib.list(f);
    if (a.has("--json")) {
        json j = {{"library", lib.path()}, {"count", rows.size()}, {"fabrics", json::array()}};
        for (const auto& r : rows) j["fabrics"].push_back(record_json(r, false));
        std::cout << cli::dump_json(j) << "\n";
        return 0;
    }
    std::printf("%-34s %-22s %8s %7s %10s  %s\n", "name", "composition", "g/m^2", "D [%]", "fit", "modified");
    for (const auto& r : rows)
        std::printf("%-34s %-22s %8.1f %7s %10s  %s\n", r.name.c_str(), r.composition.substr(0, 22).c_str(),
                    r.areal_density_kg_m2 * 1e3, fmt_opt(r.drape_coefficient_percent, "%.1f").c_str(),
                    fmt_opt(r.fit_quality, "%.3g").c_str(), r.modified.c_str());
    std::printf("%zu fabric(s) in %s\n", rows.size(), lib.path().c_str());
    return 0;
}

/// drape library show NAME: one fabric, as every command resolves its name.
int library_show(const std::vector<std::string>& rest)
{
    cli::Args a(rest, with_common({}), {"--json"});
    if (a.positionals().size() != 1) throw cli::UsageError("library show needs one NAME");
    const FabricLibrary lib = open_library_of(a, FabricLibrary::Mode::ReadOnly);
    // The name as every command resolves it ("silk": the starter's "Silk (class preset)").
    const FabricRecord r = library_fabric(lib, a.positionals().front());
    const bool stored = r.revision > 0;
    if (a.has("--json")) {
        json j = record_json(r, true);
        j["stored"] = stored; // false: a starter fabric this library does not hold
        std::cout << cli::dump_json(j) << "\n";
        return 0;
    }
    std::printf("name:         %s\ncomposition:  %s\nformat:       %s\nweight:       %.1f g/m^2\n", r.name.c_str(),
                r.composition.c_str(), r.format.c_str(), r.areal_density_kg_m2 * 1e3);
    if (!stored)
        std::printf("stored:       no - the starter fabric built into drape, not in %s (drape library add '%s' stores it)\n",
                    lib.path().c_str(), r.name.c_str());
    std::printf("D:            %s %%\nfit quality:  %s\ncreated:      %s\nmodified:     %s (revision %d)\n",
                fmt_opt(r.drape_coefficient_percent, "%.1f").c_str(), fmt_opt(r.fit_quality, "%.4g").c_str(),
                stored ? r.created.c_str() : "-", stored ? r.modified.c_str() : "-", r.revision);
    if (!r.preset.is_seed()) {
        std::printf("parameters:\n");
        for (const auto& s : cloth::param_table())
            std::printf("  %-24s %-14.6g %s\n", std::string(s.key).c_str(), r.preset.params[s.id], std::string(s.unit).c_str());
    } else {
        std::printf("seed-19 constants:\n%s\n", cli::dump_json(fabric::seed_to_json(*r.preset.seed)).c_str());
    }
    for (const char* k : {"source", "notes", "provenance"})
        if (r.preset_json.contains(k)) std::printf("%s: %s\n", k, cli::dump_json(r.preset_json[k], -1).c_str());
    return 0;
}

/// drape library add FILE, drape library update NAME FILE: stores a preset, or replaces a stored one keeping its name.
int library_add(const std::vector<std::string>& rest, const std::string& sub)
{
    cli::Args a(rest, with_common({"--name"}), {"--json", "--replace"});
    const bool update = sub == "update";
    if (update ? a.positionals().size() != 2 : a.positionals().size() != 1)
        throw cli::UsageError(update ? "library update needs NAME FILE" : "library add needs one preset FILE (or seed-table1)");
    const std::string file = a.positionals().back();
    if (const auto n = a.get("--name")) check_name_flag(*n);
    if (update) check_name_flag(a.positionals().front(), "NAME");
    const fabric::FabricPreset p = resolve_fabric(file, a.get_or("--library", ""));
    FabricLibrary lib = open_library_of(a, FabricLibrary::Mode::ReadWrite);
    std::string name = update ? a.positionals().front() : a.get_or("--name", "");
    if (update) {
        lib.update(name, p);
    } else {
        if (name.empty()) name = p.name;
        if (name.empty() || name == "unnamed") throw ParameterError(file + ": the preset has no name; pass --name");
        if (a.has("--replace") && lib.find(name)) lib.update(name, p);
        else lib.add(p, name);
    }
    const FabricRecord r = lib.get(name);
    if (a.has("--json")) std::cout << cli::dump_json(record_json(r, false)) << "\n";
    else std::printf("%s '%s' (revision %d) in %s\n", update ? "updated" : "stored", r.name.c_str(), r.revision, lib.path().c_str());
    return 0;
}

/// drape library rename OLD NEW.
int library_rename(const std::vector<std::string>& rest)
{
    cli::Args a(rest, with_common({}), {"--json"});
    if (a.positionals().size() != 2) throw cli::UsageError("library rename needs OLD NEW");
    check_name_flag(a.positionals()[1], "NEW");
    FabricLibrary lib = open_library_of(a, FabricLibrary::Mode::ReadWrite);
    lib.rename(a.positionals()[0], a.positionals()[1]);
    if (a.has("--json")) std::cout << cli::dump_json(json{{"renamed", a.positionals()[0]}, {"to", a.positionals()[1]}}) << "\n";
    else std::printf("renamed '%s' to '%s'\n", a.positionals()[0].c_str(), a.positionals()[1].c_str());
    return 0;
}

/// drape library remove NAME.
int library_remove(const std::vector<std::string>& rest)
{
    cli::Args a(rest, with_common({}), {"--json"});
    if (a.positionals().empty()) throw cli::UsageError("library remove needs NAME [NAME ...]");
    FabricLibrary lib = open_library_of(a, FabricLibrary::Mode::ReadWrite);
    lib.remove(a.positionals()); // all or nothing
    if (a.has("--json")) std::cout << cli::dump_json(json{{"removed", a.positionals()}, {"count", lib.count()}}) << "\n";
    else std::printf("removed %zu fabric(s); %d left\n", a.positionals().size(), lib.count());
    return 0;
}

/// drape library export NAME | --all: a preset as drapekit, seed-19, U3M or Blender cloth settings, or the whole library.
int library_export(const std::vector<std::string>& rest)
{
    cli::Args a(rest, with_common({"--out", "--format"}), {"--json", "--all"});
    const FabricLibrary lib = open_library_of(a, FabricLibrary::Mode::ReadOnly);
    json doc;
    std::string what;
    if (a.has("--all")) {
        if (!a.positionals().empty()) throw cli::UsageError("library export --all takes no NAME");
        doc = lib.export_all();
        what = std::to_string(doc["fabrics"].size()) + " fabric(s)";
    } else {
        if (a.positionals().size() != 1) throw cli::UsageError("library export needs NAME or --all");
        const std::string f = a.get_or("--format", "drapekit");
        if (f != "u3m" && f != "blender" && f != "drapekit" && f != "drapekit-fabric" && f != "seed19" && f != "seed-19")
            throw cli::UsageError("--format: '" + f + "' must be drapekit, seed19, u3m or blender");
        // The name as every command resolves it ("silk": the starter's "Silk (class preset)").
        const FabricRecord r = library_fabric(lib, a.positionals().front());
        const std::string& name = r.name;
        what = "'" + name + "'";
        if (f == "u3m") {
            doc = preset_to_u3m(r.preset, {r.created, r.modified});
        } else if (f == "blender") {
            // A Python script, not JSON.
            const std::string script = preset_to_blender_script(r.preset);
            const auto out = a.get("--out");
            if (out && *out != "-") {
                drape::write_file_atomic(*out, script);
                if (a.has("--json")) std::cout << cli::dump_json(json{{"exported", what}, {"out", *out}, {"format", "blender"}}) << "\n";
                else std::printf("exported %s to %s (Blender cloth settings: run it in Blender with the garment selected)\n",
                                 what.c_str(), out->c_str());
            } else {
                std::cout << script;
            }
            return 0;
        } else {
            PresetFormat pf;
            if (f == "drapekit" || f == "drapekit-fabric") pf = PresetFormat::Drapekit;
            else if (f == "seed19" || f == "seed-19") pf = PresetFormat::Seed19;
            else throw cli::UsageError("--format: '" + f + "' must be drapekit, seed19, u3m or blender");
            if (r.revision > 0) doc = lib.export_preset(name, pf);
            else if (pf == PresetFormat::Drapekit) doc = r.preset_json; // a starter this library does not hold
            else throw ParameterError("starter fabric '" + name + "' holds continuum parameters; the seed's 19 grid constants "
                                      "describe one particular grid, so it is exported as drapekit-fabric only");
        }
    }
    const auto out = a.get("--out");
    write_output(doc, out);
    if (out && *out != "-") {
        if (a.has("--json")) std::cout << cli::dump_json(json{{"exported", what}, {"out", *out}}) << "\n";
        else std::printf("exported %s to %s\n", what.c_str(), out->c_str());
    }
    return 0;
}

/// drape library import FILE | FOLDER: presets, a U3M material or a library export, all or nothing.
int library_import(const std::vector<std::string>& rest)
{
    cli::Args a(rest, with_common({"--on-conflict", "--name"}), {"--json"});
    if (a.positionals().size() != 1) throw cli::UsageError("library import needs one FILE");
    const std::string file = a.positionals().front();
    const OnConflict oc = parse_conflict(a.get_or("--on-conflict", "fail"));
    json j;
    std::error_code ec;
    if (std::filesystem::is_directory(file, ec)) {
        // A folder of preset files (e.g. data/library): all of them, in one transaction.
        std::vector<std::filesystem::path> files;
        for (const auto& e : std::filesystem::directory_iterator(file))
            if (e.path().extension() == ".json") files.push_back(e.path());
        std::sort(files.begin(), files.end());
        if (files.empty()) throw FileError(file + ": no *.json preset files in this folder");
        j = json::array();
        for (const auto& f : files) {
            json one = drape::read_json_file(f.string());
            fabric::fabric_from_json(one, f.string()); // names the file if it is bad
            j.push_back(std::move(one));
        }
    } else {
        j = drape::read_json_file(file);
    }
    std::string u3m_note;
    if (is_u3m(j)) j = fabric::fabric_to_json(preset_from_u3m(j, file, &u3m_note)); // a U3M material: its preset
    FabricLibrary lib = open_library_of(a, FabricLibrary::Mode::ReadWrite);
    ImportReport rep;
    if (const auto n = a.get("--name")) check_name_flag(*n);
    if (j.is_array() || (j.is_object() && j.contains("format") && j["format"] == "drapekit-fabric-library")) {
        if (a.get("--name")) throw cli::UsageError("--name applies to a single preset, not a library export");
        rep = lib.import_all(j, file, oc);
    } else {
        const auto before = lib.count();
        const auto id = lib.import_preset(j, file, a.get_or("--name", ""), oc);
        (void)id;
        rep.names.push_back(a.get_or("--name", fabric::fabric_from_json(j, file).name));
        if (lib.count() > before) {
            rep.added = 1;
        } else {
            rep.replaced = oc == OnConflict::Replace ? 1 : 0;
            rep.skipped = oc == OnConflict::Skip ? 1 : 0;
        }
    }
    if (a.has("--json")) {
        json out = {{"added", rep.added}, {"replaced", rep.replaced}, {"skipped", rep.skipped},
                    {"renamed", rep.renamed}, {"names", rep.names}, {"count", lib.count()}};
        if (!u3m_note.empty()) out["u3m"] = u3m_note;
        std::cout << cli::dump_json(out) << "\n";
    } else {
        if (!u3m_note.empty()) std::printf("U3M: %s\n", u3m_note.c_str());
        std::printf("imported from %s: %d added, %d replaced, %d skipped, %d renamed; %d fabric(s) in %s\n", file.c_str(),
                    rep.added, rep.replaced, rep.skipped, rep.renamed, lib.count(), lib.path().c_str());
    }
    return 0;
}

int run_library(const std::vector<std::string>& argv)
{
    if (argv.empty()) throw cli::UsageError("library needs a sub-command: list, show, add, update, rename, remove, export, import");
    const std::string sub = argv.front();
    const std::vector<std::string> rest(argv.begin() + 1, argv.end());
    if (sub == "list") return library_list(rest);
    if (sub == "show") return library_show(rest);
    if (sub == "add" || sub == "update") return library_add(rest, sub);
    if (sub == "rename") return library_rename(rest);
    if (sub == "remove") return library_remove(rest);
    if (sub == "export") return library_export(rest);
    if (sub == "import") return library_import(rest);
    throw cli::UsageError("library: unknown sub-command '" + sub + "'");
}

DRAPE_COMMAND({"library", "manage the fabric library (SQLite): list, show, add, remove, export, import",
               "usage: drape library SUBCOMMAND [--library PATH] ...\n"
               "  The library file: --library PATH, else $DRAPE_LIBRARY, else\n"
               "  $XDG_DATA_HOME/drapekit/library.sqlite (~/.local/share/drapekit/library.sqlite).\n"
               "  The default library is created on first use with the starter fabrics (silk, cotton, wool, denim).\n"
               "  Every sub-command takes --json for machine-readable output.\n"
               "\n"
               "  list   [--search TEXT] [--name S] [--composition S] [--weight-min G] [--weight-max G] (g/m^2)\n"
               "         [--d-min D] [--d-max D] (percent: 65 or 65%) [--fit-min Q] [--fit-max Q] (reduced chi-square)\n"
               "         [--since DATE] [--until DATE] (modified, ISO 8601) [--sort name|weight|d|modified|fit] [--desc] [--limit N]\n"
               "  show   NAME                       parameters, composition, D, fit, dates\n"
               "  add    FILE [--name NAME] [--replace]   a preset JSON (drapekit-fabric or seed-19), seed-table1 or a starter (silk, ...)\n"
               "  update NAME FILE                  replace the stored preset, keep the name\n"
               "  rename OLD NEW\n"
               "  remove NAME [NAME ...]\n"
               "  export NAME [--format drapekit|seed19|u3m|blender] [--out FILE]   one preset (stdout without --out):\n"
               "                                    u3m = U3M 1.1 material (weight, thickness; our parameters in\n"
               "                                    custom.drapekit); blender = a Python script setting Blender's cloth\n"
               "  export --all [--out FILE]         the whole library as one JSON document\n"
               "  import FILE|FOLDER [--name NAME] [--on-conflict fail|skip|replace|rename]\n"
               "                                    a preset, a U3M material (.u3m JSON), a whole-library export or a\n"
               "                                    folder of presets\n"
               "                                    (e.g. data/library, the starter library); all or nothing",
               run_library});

} // namespace cmd_library
#endif
