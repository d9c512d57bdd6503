// `drape measure`: a drape-test record, a single top photo, or a folder of
// photos -> calibrated measurements.
#include "cli/command.hpp"
#include "cli/photo_manifest.hpp"
#include "cli/progress.hpp"

#ifdef HAVE_DRAPE_CAPTURE
#include "engine/capture/export.hpp"
#include "engine/capture/measure.hpp"
#include "engine/capture/report.hpp"
#include "engine/core/error.hpp"
#include "engine/core/io.hpp"
#include "engine/core/text.hpp"
#include "engine/core/units.hpp"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

namespace cmd_measure {

using namespace drape;
namespace fs = std::filesystem;
using nlohmann::json;

double length_mm(const cli::Args& a, const std::string& flag)
{
    return 1e3 * a.get_length(flag, std::nan(""));
}

/// --specimen-angle DEG|auto as meta.json's angle_deg.
std::optional<json> angle_flag(const cli::Args& a)
{
    const auto ang = a.get("--specimen-angle");
    if (!ang) return std::nullopt;
    if (*ang == "auto") return json("auto");
    return json(a.get_double("--specimen-angle", 0));
}

/// "300mm" -> round; "300x400mm" or "30x40cm" -> rectangle.
json specimen_json(const std::string& text, const cli::Args& a)
{
    const auto x = text.find('x');
    json sp;
    if (x == std::string::npos) {
        sp = {{"shape", "round"}, {"diameter_mm", 1e3 * parse_length(text, "--specimen")}};
    } else {
        std::string w = text.substr(0, x), l = text.substr(x + 1);
        // A unit on the second number only applies to both ("300x400mm").
        std::size_t u = l.find_first_not_of("0123456789.eE+-");
        const std::string unit = u == std::string::npos ? "" : l.substr(u);
        if (w.find_first_not_of("0123456789.eE+-") == std::string::npos) w += unit;
        sp = {{"shape", "rectangle"}, {"width_mm", 1e3 * parse_length(w, "--specimen")}, {"length_mm", 1e3 * parse_length(l, "--specimen")}};
    }
    if (auto ang = angle_flag(a)) sp["angle_deg"] = *ang;
    return sp;
}

/// The meta.json the single-photo flags describe (documented in docs/capture.md).
/// With a manifest row (`row`, at `row_where`), the sizes it gives need no flag;
/// apply_manifest_row then puts its values in.
json meta_from_flags(const cli::Args& a, const std::string& image, const std::string& id, const cli::ManifestRow* row = nullptr,
                     const std::string& row_where = "")
{
    json conf;
    const auto disc = a.get("--disc");
    const auto spec = a.get("--specimen");
    if (row && (!disc || !spec)) {
        if (!disc && !row->disc_mm)
            throw FileError(row_where + ": column 'disc_mm' is empty (or missing) for " + printable(image) + " and there is no --disc");
        if (!spec && !row->specimen_width_mm)
            throw FileError(row_where + ": column 'specimen_mm' is empty (or missing) for " + printable(image) + " and there is no --specimen");
    } else if (!disc || !spec) {
        throw cli::UsageError("a photo needs --disc DIAMETER and --specimen DIAMETER|WxL");
    }
    if (disc) conf["support_disc_diameter_D2_mm"] = length_mm(a, "--disc");
    if (spec) conf["specimen"] = specimen_json(*spec, a);
    else if (auto ang = angle_flag(a)) conf["specimen"] = {{"angle_deg", *ang}}; // for the row's rectangle
    if (a.has("--pedestal-height")) conf["pedestal_height_mm"] = length_mm(a, "--pedestal-height");
    json scale;
    const std::string s = a.get_or("--scale", "disc");
    if (s == "disc") {
        scale["source"] = "disc";
    } else if (s == "markers") {
        scale["source"] = "markers";
        if (!a.has("--marker-size")) throw cli::UsageError("--scale markers needs --marker-size (the black square's edge, e.g. 50mm)");
        scale["size_mm"] = length_mm(a, "--marker-size");
        scale["dictionary"] = a.get_or("--marker-dict", "DICT_4X4_50");
    } else if (s == "chessboard") {
        scale["source"] = "chessboard";
        const std::string b = a.get_or("--board", "");
        int c = 0, r = 0;
        if (std::sscanf(b.c_str(), "%dx%d", &c, &r) != 2)
            throw cli::UsageError("--scale chessboard needs --board COLSxROWS (inner corners, e.g. 9x6) and --square 25mm");
        scale["inner_corners"] = {c, r};
        scale["square_mm"] = a.has("--square") ? length_mm(a, "--square") : 25.0;
    } else if (s.rfind("px-per-mm=", 0) == 0) {
        double v = 0;
        if (!parse_number(s.substr(10), v) || !(v > 0)) throw cli::UsageError("--scale px-per-mm=N: N must be a positive number");
        scale["source"] = "px-per-mm";
        scale["px_per_mm"] = v;
    } else {
        throw cli::UsageError("--scale must be disc, markers, chessboard or px-per-mm=N, got '" + s + "'");
    }
    if (a.has("--reference-height")) scale["height_mm"] = length_mm(a, "--reference-height");
    json tp = {{"image", image}, {"scale", scale}};
    if (auto d = a.get("--disc-px")) {
        double x = 0, y = 0, r = 0;
        const int n = std::sscanf(d->c_str(), "%lf,%lf,%lf", &x, &y, &r);
        if (n < 2) throw cli::UsageError("--disc-px X,Y[,R]: the disc centre (and radius) in pixels");
        tp["disc_px"] = {{"centre", {x, y}}};
        if (n == 3) tp["disc_px"]["radius"] = r;
    }
    if (a.has("--camera-height")) tp["camera_height_mm"] = length_mm(a, "--camera-height");
    if (a.has("--focal-px")) tp["focal_px"] = a.get_double("--focal-px", 0);
    if (auto p = a.get("--perspective"); p && *p != "calibration") tp["perspective"] = *p;
    return {{"specimen_id", id}, {"configuration", conf}, {"top_photo", tp}};
}

/// A manifest row's values over a photo's meta.json (from the flags or a --meta
/// template). `where` is "M.csv:LINE".
void apply_manifest_row(json& meta, const cli::ManifestRow& r, const std::string& where)
{
    json& conf = meta["configuration"];
    if (r.disc_mm) conf["support_disc_diameter_D2_mm"] = *r.disc_mm;
    if (r.specimen_width_mm) {
        json sp = r.specimen_length_mm
                      ? json{{"shape", "rectangle"}, {"width_mm", *r.specimen_width_mm}, {"length_mm", *r.specimen_length_mm}}
                      : json{{"shape", "round"}, {"diameter_mm", *r.specimen_width_mm}};
        // A rectangle keeps the default's orientation unless the row gives its own.
        if (r.specimen_length_mm && conf.contains("specimen") && conf["specimen"].is_object() && conf["specimen"].contains("angle_deg"))
            sp["angle_deg"] = conf["specimen"]["angle_deg"];
        conf.erase("specimen_diameter_D1_mm");
        conf["specimen"] = sp;
    }
    if (r.specimen_angle_deg || r.specimen_angle_auto) {
        const bool round = !conf.contains("specimen") || !conf["specimen"].is_object() || conf["specimen"].value("shape", "round") == "round";
        if (round)
            throw FileError(where + ": column 'specimen_angle_deg': '" + printable(r.specimen_angle_text) +
                            "' turns a rectangle, square or polygon, and this photo's specimen is round");
        conf["specimen"]["angle_deg"] = r.specimen_angle_auto ? json("auto") : json(*r.specimen_angle_deg);
    }
    // The disc centre as --disc-px X,Y gives it (a declared radius stays).
    if (r.centre_x_px) meta["top_photo"]["disc_px"]["centre"] = {*r.centre_x_px, *r.centre_y_px};
}

/// The markers or chessboard of the scale declaration `decl`, found once in the
/// calibration photo `given` (--scale-from).
capture::ScaleCalibration read_calibration(const std::string& given, const record::TopPhoto& decl)
{
    if (decl.scale != record::ScaleSource::Markers && decl.scale != record::ScaleSource::Chessboard)
        throw cli::UsageError(std::string("--scale-from ") + printable(given) + ": the scale is '" + record::to_string(decl.scale) +
                              "'; a calibration photo is read for --scale markers or --scale chessboard (the disc rim is found in "
                              "each photo, a px/mm needs no photo)");
    std::error_code ec;
    if (!fs::is_regular_file(fs::path(given), ec)) throw FileError(given + ": no such calibration photo (--scale-from)");
    return capture::read_scale_calibration(decl, given);
}

capture::MeasureOptions options(const cli::Args& a)
{
    capture::MeasureOptions opt;
    opt.rays = a.get_int("--rays", 720, 90, 7200);
    opt.calibrate = !a.has("--no-calibrate");
    opt.metrics.relative_prominence = a.get_double("--node-prominence", opt.metrics.relative_prominence);
    if (!(opt.metrics.relative_prominence >= 0 && opt.metrics.relative_prominence < 1))
        throw cli::UsageError("--node-prominence must be in [0, 1)");
    opt.perspective = a.get_or("--perspective", "auto");
    static const std::set<std::string> persp = {"auto", "none", "disc-plane", "hem", "calibration"};
    if (!persp.count(opt.perspective))
        throw cli::UsageError("--perspective must be auto, none, disc-plane, hem or calibration, got '" + opt.perspective + "'");
    opt.segmentation = a.get_or("--segmentation", "auto");
    if (opt.segmentation != "auto" && opt.segmentation != "photo" && opt.segmentation != "lab")
        throw cli::UsageError("--segmentation must be auto, photo or lab, got '" + opt.segmentation + "'");
    opt.overrides.threshold = a.get_or("--threshold", "");
    if (auto mk = a.get("--mask")) {
        opt.overrides.mask = cv::imread(*mk, cv::IMREAD_GRAYSCALE);
        if (opt.overrides.mask.empty()) throw FileError(*mk + ": --mask is not a readable image");
        opt.overrides.mask_name = *mk;
    }
    return opt;
}

void print_text(const capture::Measurement& m)
{
    std::printf("record %s\n", m.specimen_id.c_str());
    if (m.top.measured) {
        const auto& tv = m.top;
        const auto& t = tv.metrics;
        std::printf("  drape coefficient  %.1f %% (+- %.1f, perspective: %s)", t.drape_coefficient_percent, tv.dc_uncertainty_percent,
                    tv.perspective.c_str());
        if (m.lab_dc_percent) std::printf("   lab %.1f %%", *m.lab_dc_percent);
        std::printf("\n");
        for (const capture::PerspectiveValue* v : {&tv.uncorrected, &tv.disc_plane, &tv.hem}) {
            if (v->model == "disc-plane" && !(m.view && m.view->single_camera && m.view->reference_height != 0.0)) continue;
            if (!v->available) continue;
            std::printf("    %-11s %5.1f %% +- %.1f  (", v->model == "none" ? "uncorrected" : v->model.c_str(), v->dc_percent,
                        v->uncertainty_percent);
            for (std::size_t i = 0; i < v->terms.size(); ++i)
                std::printf("%s%s %.1f", i ? ", " : "", v->terms[i].name.c_str(), v->terms[i].points);
            std::printf(")\n");
        }
        std::printf("  perspective        %s: %s\n", tv.perspective.c_str(), tv.perspective_reason.c_str());
        std::printf("  nodes              %d at", t.node_count);
        for (double th : t.node_angles_rad) std::printf(" %.0f", th * 180 / M_PI);
        std::printf(" deg\n  radius mean/min/max %.1f / %.1f / %.1f mm\n", t.mean_radius_m * 1e3, t.min_radius_m * 1e3,
                    t.max_radius_m * 1e3);
        std::printf("  segmentation       %s\n", tv.segmentation_method.c_str());
    }
    if (m.view && m.view->single_camera) {
        const auto& g = *m.view;
        std::printf("  scale              %s\n", g.source_text.c_str());
        std::printf("  camera height      %.0f +- %.0f mm (%s)\n", g.camera_height * 1e3, g.camera_height_sigma * 1e3,
                    g.camera_height_source.c_str());
        std::printf("  disc centre        %.1f, %.1f px (%s)\n", g.centre_px.x(), g.centre_px.y(), g.centre_source.c_str());
    }
    if (m.hem_min_height)
        std::printf("  lowest hem         z = %.1f mm (%s)\n", *m.hem_min_height * 1e3, m.hem_min_source.c_str());
    if (m.side.pedestal.measured)
        std::printf("  pedestal           %.1f +- %.1f mm across in the side photo (declared %.1f mm%s)\n", m.side.pedestal.diameter * 1e3,
                    m.side.pedestal.diameter_sigma * 1e3, m.side.pedestal.declared * 1e3, m.side.pedestal.differs ? ": DIFFERS" : "");
    if (m.free_strip_bending_bound)
        std::printf("  free-strip bound   B <= %.2g N*m (a linear bending that drapes to this D; docs/model-discrepancy.md)\n",
                    *m.free_strip_bending_bound);
    if (m.top_calibration && m.top_calibration->ok)
        std::printf("  top camera         %zu boards, reprojection %.2f px, declared pose off by %.2f px\n",
                    m.top_calibration->boards_found.size(), m.top_calibration->rms_px_measured, m.top_calibration->max_shift_px);
    for (const auto& c : m.contours) {
        std::printf("  contour %4.0f mm    mean r %.1f mm, %d harmonics, fit RMS %.2f mm (noise %.2f mm), |c1..c4| =",
                    c.depth * 1e3, c.mean_radius * 1e3, c.harmonics, c.residual_rms * 1e3, c.noise_sigma * 1e3);
        for (int k = 1; k <= std::min(4, c.harmonics); ++k) std::printf(" %.1f", c.fit.magnitude(k) * 1e3);
        std::printf(" mm\n");
    }
    // File names and cells in these come from the record: printed escaped.
    for (const auto& s : m.not_measured) std::printf("  not measured: %s\n", printable(s, 1000).c_str());
    for (const auto& s : m.warnings) std::printf("  warning: %s\n", printable(s, 1000).c_str());
}

/// Exit code of one measurement: 1 when refused, when a photo gave no D, or
/// when a file the record names is there but bad (what was measured is printed
/// first; the error names the file, line, field and value).
int verdict(const capture::Measurement& m, bool photo, const std::string& what)
{
    for (const auto& e : m.bad_files) std::cerr << "drape measure: " << printable(e, 400) << "\n";
    const int bad = m.bad_files.empty() ? 0 : 1;
    if (bad)
        std::cerr << "drape measure: " << printable(what) << ": " << m.bad_files.size()
                  << " file(s) of the record could not be read (bad input, exit 1); what could be measured is printed\n";
    if (m.refused) {
        std::cerr << "drape measure: " << printable(what) << ": refused (" << m.refused->check << "): " << printable(m.refused->message, 1000)
                  << "\n  what to try: " << m.refused->remedy << "\n";
        return 1;
    }
    if (photo && !m.top.measured) {
        std::string why;
        for (const auto& s : m.not_measured)
            if (s.rfind("top view", 0) == 0) why = s;
        std::cerr << "drape measure: " << printable(what) << ": no drape coefficient: " << printable(why.empty() ? "top view not measured" : why, 1000) << "\n";
        return 1;
    }
    return bad;
}

void write_outputs(const cli::Args& a, const record::Record& rec, const capture::Measurement& m)
{
    if (auto path = a.get("--overlay")) {
        if (m.top_image.empty()) throw FileError(*path + ": no overlay: the record has no readable top photo");
        if (!cv::imwrite(*path, capture::draw_top_overlay(rec, m))) throw FileError(*path + ": cannot write the overlay");
    }
    if (auto path = a.get("--texture")) {
        if (!m.top.measured) throw FileError(*path + ": no texture: the top view was not measured");
        const cv::Mat tex = capture::rectified_texture(rec, m);
        if (!cv::imwrite(*path, tex)) throw FileError(*path + ": cannot write the texture");
        fs::path p(*path);
        if (p.extension() == ".bmp") cv::imwrite(p.replace_extension(".png").string(), tex);
    }
    if (auto path = a.get("--mesh")) capture::write_obj(capture::contour_surface(rec, m), *path);
}

// ---- batch ---------------------------------------------------------------------

std::string csv_cell(const std::string& s)
{
    if (s.find_first_of(",\"\n") == std::string::npos) return s;
    std::string o = "\"";
    for (char c : s) o += c == '"' ? std::string("\"\"") : std::string(1, c);
    return o + "\"";
}

std::string num_cell(double v, int prec = 2)
{
    if (!std::isfinite(v)) return "";
    char b[64];
    std::snprintf(b, sizeof b, "%.*f", prec, v);
    return b;
}

/// The specimen as the batch table gives it: "300" (round, mm), "300x400" (a
/// rectangle, with " at 20 deg" or " at auto"), else the shape in words.
std::string specimen_cell(const record::Specimen& sp)
{
    if (sp.shape == record::Specimen::Shape::Round) return format_value(2e3 * sp.radius);
    if (sp.shape == record::Specimen::Shape::Rectangle)
        return format_value(1e3 * sp.width) + "x" + format_value(1e3 * sp.length) + " at " +
               (sp.angle_from_photo ? std::string("auto") : format_value(sp.angle * 180 / M_PI) + " deg");
    return sp.describe();
}

int run_batch(const cli::Args& a, capture::MeasureOptions opt)
{
    const fs::path folder = *a.get("--batch");
    std::error_code ec;
    if (!fs::is_directory(folder, ec)) throw FileError(folder.string() + ": --batch needs a folder of photos");
    std::vector<fs::path> photos;
    for (const auto& e : fs::directory_iterator(folder, ec)) {
        const std::string ext = ascii_lower(e.path().extension().string());
        if (e.is_regular_file() && (ext == ".jpg" || ext == ".jpeg" || ext == ".png" || ext == ".tif" || ext == ".tiff" || ext == ".bmp"))
            photos.push_back(e.path());
    }
    std::sort(photos.begin(), photos.end());
    if (photos.empty()) throw FileError(folder.string() + ": no photos (.jpg, .jpeg, .png, .tif, .bmp) in the folder");
    const auto table = a.get("--table");
    if (!table) throw cli::UsageError("--batch needs --table OUT.csv or OUT.json");
    // The table is what its name says: CSV or JSON, nothing written under another name.
    const std::string table_ext = ascii_lower(fs::path(*table).extension().string());
    if (table_ext != ".csv" && table_ext != ".json")
        throw cli::UsageError("--table " + printable(*table) + ": the table is written as CSV (.csv) or JSON (.json), not '" +
                              printable(table_ext.empty() ? std::string("no extension") : table_ext) + "'");
    const bool as_json = table_ext == ".json";
    // One calibration for every photo: a meta.json template (--meta), or the flags;
    // per photo, a manifest's row over it.
    json templ;
    if (auto mt = a.get("--meta")) templ = parse_json(read_file(*mt, std::size_t(4) << 20), *mt);
    std::optional<cli::PhotoManifest> manifest;
    if (auto mf = a.get("--manifest")) {
        std::vector<std::string> names;
        for (const auto& p : photos) names.push_back(p.filename().string());
        manifest = cli::read_photo_manifest(*mf, folder.string(), names);
    }
    const std::string defaults = templ.is_null() ? "the command line" : printable(*a.get("--meta"));
    auto row_of = [&](const fs::path& p) { return manifest ? manifest->find(p.filename().string()) : nullptr; };
    auto meta_for = [&](const fs::path& p) {
        const std::string name = p.filename().string();
        const cli::ManifestRow* row = row_of(p);
        const std::string row_where = row ? manifest->where(*row) : std::string();
        json meta = templ.is_null() ? meta_from_flags(a, name, p.stem().string(), row, row_where) : templ;
        if (!templ.is_null()) {
            meta["top_photo"]["image"] = name;
            meta["specimen_id"] = p.stem().string();
        }
        if (row) apply_manifest_row(meta, *row, row_where);
        return meta;
    };
    auto record_for = [&](const fs::path& p) {
        const cli::ManifestRow* row = row_of(p);
        return record::parse_meta_json(meta_for(p), folder,
                                       defaults + (row ? " and " + manifest->where(*row) : std::string()) + " for " + p.filename().string());
    };
    if (manifest) {
        // Every photo's set-up is checked before any is measured: a bad row stops
        // the batch with no table written.
        std::vector<std::string> unlisted;
        for (const auto& p : photos) {
            if (!row_of(p)) {
                unlisted.push_back(printable(p.filename().string()));
                if (templ.is_null() && (!a.has("--disc") || !a.has("--specimen")))
                    throw FileError(printable(manifest->file) + ": " + printable(p.filename().string()) + " is not in the manifest and there is no " +
                                    (a.has("--disc") ? "--specimen" : "--disc") + " for it on the command line");
            }
            (void)record_for(p);
        }
        if (!unlisted.empty()) {
            std::string list;
            for (std::size_t i = 0; i < unlisted.size() && i < 5; ++i) list += (i ? ", " : "") + unlisted[i];
            if (unlisted.size() > 5) list += ", ...";
            std::fprintf(stderr, "manifest %s: %zu of %zu photos are not in it and are measured with %s's values (%s)\n",
                         printable(manifest->file).c_str(), unlisted.size(), photos.size(), defaults.c_str(), list.c_str());
        }
    }
    if (auto sf = a.get("--scale-from")) {
        // Read once, before any photo is measured, with the photos' own scale declaration.
        const record::Record first = record_for(photos.front());
        opt.scale_calibration = read_calibration(*sf, *first.top_photo);
        const auto& cal = *opt.scale_calibration;
        std::fprintf(stderr, "scale for every photo: %s, found in %s (%d x %d px)\n", cal.description.c_str(), printable(cal.photo).c_str(),
                     cal.width, cal.height);
    }
    cli::prepare_output_file(*table, "--table");
    std::optional<fs::path> overlays;
    if (auto d = a.get("--overlays")) {
        cli::prepare_output_dir(*d, "--overlays");
        overlays = *d;
    }
    json rows = json::array();
    std::ostringstream csv;
    csv << "photo,status,check,drape_coefficient_percent,uncertainty_percent,perspective,uncorrected_percent,disc_plane_percent,"
           "hem_percent,hem_uncertainty_percent,nodes,area_mm2,scale,px_per_mm,camera_height_mm,camera_height_known,centre_x_px,centre_y_px,"
           "centre_source,centre_bound_mm,disc_mm,specimen_mm,manifest_line,message\n";
    int failed = 0;
    const auto t0 = std::chrono::steady_clock::now();
    for (std::size_t i = 0; i < photos.size(); ++i) {
        const fs::path& p = photos[i];
        const std::string name = p.filename().string();
        // File names are untrusted text: escape sequences and control bytes are
        // escaped (\x1B) on the terminal and in the CSV; the JSON escapes them itself.
        const std::string shown = printable(name, 400);
        const cli::ManifestRow* row = row_of(p);
        json row_json = {{"photo", name}};
        std::string status = "measured", check, message;
        capture::Measurement m;
        std::optional<record::Record> rec;
        try {
            rec = record_for(p);
            m = capture::measure_record(*rec, opt);
            if (overlays && !m.top_image.empty())
                cv::imwrite((*overlays / (p.stem().string() + "-overlay.png")).string(), capture::draw_top_overlay(*rec, m));
            if (m.refused) {
                status = "refused";
                check = m.refused->check;
                message = m.refused->message + " -- try: " + m.refused->remedy;
            } else if (!m.top.measured) {
                status = "not measured";
                for (const auto& s : m.not_measured) message += (message.empty() ? "" : "; ") + s;
            }
        } catch (const Error& e) {
            status = "error";
            message = e.what();
        } catch (const cv::Exception& e) {
            // OpenCV on a photo it cannot take: this photo's row, not the whole run.
            status = "error";
            message = name + ": OpenCV: " + e.what();
        }
        message = printable(message, 1000);
        if (status != "measured") ++failed;
        const auto& tv = m.top;
        const bool ok = status == "measured";
        const double D = ok ? tv.metrics.drape_coefficient_percent : std::nan("");
        const double disc_mm = rec ? 2e3 * rec->R2 : std::nan("");
        const std::string specimen = rec ? specimen_cell(rec->specimen) : "";
        const std::string scale = m.view ? std::string(record::to_string(m.view->source)) +
                                               (m.view->calibration_photo.empty() ? "" : " in " + printable(m.view->calibration_photo, 400))
                                         : "";
        row_json["status"] = status;
        row_json["check"] = check;
        row_json["message"] = message;
        row_json["disc_mm"] = rec ? json(disc_mm) : json(nullptr);
        row_json["specimen_mm"] = rec ? json(specimen) : json(nullptr);
        row_json["manifest_line"] = row ? json(row->line) : json(nullptr);
        if (ok) {
            row_json["measurement"] = capture::to_json(m);
        }
        rows.push_back(row_json);
        csv << csv_cell(shown) << "," << status << "," << check << "," << num_cell(D) << ","
            << num_cell(ok ? tv.dc_uncertainty_percent : std::nan("")) << "," << (ok ? tv.perspective : "") << ","
            << num_cell(ok ? tv.uncorrected.dc_percent : std::nan("")) << "," << num_cell(ok ? tv.disc_plane.dc_percent : std::nan("")) << ","
            << num_cell(ok ? tv.hem.dc_percent : std::nan("")) << "," << num_cell(ok ? tv.hem.uncertainty_percent : std::nan("")) << ","
            << (ok ? std::to_string(tv.metrics.node_count) : "") << "," << num_cell(ok ? tv.metrics.shadow_area_m2 * 1e6 : std::nan(""), 0) << ","
            << csv_cell(scale) << "," << num_cell(m.view ? m.view->scale_px_per_m * 1e-3 : std::nan(""), 4) << ","
            << num_cell(m.view ? m.view->camera_height * 1e3 : std::nan(""), 0) << ","
            << (m.view ? (m.view->camera_height_known ? "yes" : "no") : "") << "," << num_cell(m.view ? m.view->centre_px.x() : std::nan(""), 1)
            << "," << num_cell(m.view ? m.view->centre_px.y() : std::nan(""), 1) << "," << csv_cell(m.view ? m.view->centre_source : "") << ","
            << num_cell(m.view ? m.view->centre_bound * 1e3 : std::nan(""), 0) << "," << (rec ? format_value(disc_mm) : "") << ","
            << csv_cell(specimen) << "," << (row ? std::to_string(row->line) : "") << "," << csv_cell(message) << "\n";
        const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        // The table so far, rewritten atomically after every photo: a later
        // failure or an interrupted run keeps every row measured before it.
        write_file_atomic(*table, as_json ? cli::dump_json(json({{"folder", folder.string()}, {"photos", rows}}), 1) + "\n" : csv.str());
        std::fprintf(stderr, "[%zu/%zu] %-28s %s", i + 1, photos.size(), shown.c_str(), status.c_str());
        if (ok) std::fprintf(stderr, "  D = %.1f %% +- %.1f (%s)", D, tv.dc_uncertainty_percent, tv.perspective.c_str());
        else if (!check.empty()) std::fprintf(stderr, " (%s)", check.c_str());
        std::fprintf(stderr, "   %.0f s, about %.0f s left\n", elapsed, elapsed / static_cast<double>(i + 1) * static_cast<double>(photos.size() - i - 1));
        if (status == "error") std::fprintf(stderr, "      %s\n", message.c_str());
    }
    std::fprintf(stderr, "%zu photos: %zu measured, %d refused or failed; table in %s\n", photos.size(),
                 photos.size() - static_cast<std::size_t>(failed), failed, printable(*table).c_str());
    return failed ? 1 : 0;
}

int run_measure(const std::vector<std::string>& argv)
{
    cli::Args a(argv,
                {"--overlay", "--rays", "--node-prominence", "--texture", "--mesh", "--top", "--disc", "--specimen",
                 "--specimen-angle", "--scale", "--marker-size", "--marker-dict", "--board", "--square", "--reference-height",
                 "--disc-px", "--camera-height", "--focal-px", "--perspective", "--threshold", "--mask", "--segmentation",
                 "--write-meta", "--batch", "--table", "--overlays", "--meta", "--pedestal-height", "--scale-from", "--manifest"},
                {"--json", "--no-calibrate"});
    capture::MeasureOptions opt = options(a);
    if (a.has("--manifest") && !a.has("--batch")) throw cli::UsageError("--manifest goes with --batch FOLDER (one row per photo of the folder)");
    if (a.has("--scale-from")) {
        if (!a.has("--batch") && !a.has("--top"))
            throw cli::UsageError("--scale-from goes with --top PHOTO or --batch FOLDER (a record's meta.json says where its own scale comes from)");
        if (a.has("--write-meta"))
            throw cli::UsageError("--write-meta cannot record --scale-from: a meta.json has no field for a separate calibration photo");
    }
    if (a.has("--batch")) {
        if (!a.positionals().empty() || a.has("--top")) throw cli::UsageError("--batch takes no RECORD_DIR or --top");
        return run_batch(a, opt);
    }
    record::Record rec;
    bool photo = false;
    std::string what;
    if (auto top = a.get("--top")) {
        if (!a.positionals().empty()) throw cli::UsageError("give either RECORD_DIR or --top PHOTO, not both");
        const fs::path p = fs::absolute(*top);
        std::error_code ec;
        if (!fs::is_regular_file(p, ec)) throw FileError(*top + ": no such photo");
        const json meta = meta_from_flags(a, p.filename().string(), p.stem().string());
        if (auto out = a.get("--write-meta")) write_file_atomic(*out, cli::dump_json(meta, 1) + "\n");
        rec = record::parse_meta_json(meta, p.parent_path(), "the command line (as meta.json)");
        if (auto sf = a.get("--scale-from")) opt.scale_calibration = read_calibration(*sf, *rec.top_photo);
        photo = true;
        what = *top;
    } else {
        if (a.positionals().size() != 1) throw cli::UsageError("expected exactly one RECORD_DIR, or --top PHOTO, or --batch FOLDER");
        rec = record::read_record(a.positionals()[0]);
        photo = rec.single_camera();
        what = a.positionals()[0];
    }
    // One measurement is one step (a second or two): a line when it starts and one when it is done.
    cli::Progress progress("measure " + rec.specimen_id, a.has("--json"));
    progress.update(-1, photo ? "scale, segmentation, outline" : "photos, calibration, contours");
    const capture::Measurement m = capture::measure_record(rec, opt);
    progress.finish();
    write_outputs(a, rec, m);
    if (a.has("--json")) std::cout << cli::dump_json(capture::to_json(m), 1) << "\n";
    else print_text(m);
    return verdict(m, photo, what);
}

DRAPE_COMMAND({"measure", "measure a drape-test record, a single top photo, or a folder of photos",
               "usage: drape measure RECORD_DIR [--json] [--overlay out.png] [--texture F.bmp] [--mesh F.obj]\n"
               "                    [--rays N] [--no-calibrate] [--node-prominence F] [--perspective P]\n"
               "                    [--threshold T] [--mask M.png] [--segmentation auto|photo|lab]\n"
               "       drape measure --top PHOTO --disc 180mm --specimen 300mm|300x400mm [--scale S] [--scale-from CALIB_PHOTO]\n"
               "                     [photo flags] [...]\n"
               "       drape measure --batch FOLDER --table OUT.csv|OUT.json [--overlays DIR] (--meta TEMPLATE.json | photo flags)\n"
               "                     [--scale-from CALIB_PHOTO] [--manifest M.csv]\n"
               "  RECORD_DIR       folder with meta.json and its photos (a lab record with cameras and contours, or a\n"
               "                   single-camera record with \"top_photo\": docs/capture.md)\n"
               "  --json           print the measurements as JSON (SI units, unit in each key)\n"
               "  --overlay FILE   write the top photo with what was counted (tinted), the traced outline, nodes,\n"
               "                   disc circle, search limit, scale reference; a refused photo shows why\n"
               "  --texture FILE   write the top view rectified to the pedestal-top plane, 0.25 mm/px (FILE.bmp also\n"
               "                   writes FILE.png)\n"
               "  --mesh FILE.obj  write the surface through the contour levels' Fourier series [m]\n"
               "  --rays N         rays traced around the axis (default 720)\n"
               "  --no-calibrate   use the declared top pose instead of solvePnP on the floor chessboards\n"
               "  --node-prominence F  a fold crest must rise F x (max r - min r) above its troughs (default 0.10)\n"
               "  --perspective P  the model D is reported with: auto (hem: the vertical projection; from an assumed\n"
               "                   camera height, with its spread in D's uncertainty, when the height is not known),\n"
               "                   none (outline in the scale reference's plane), disc-plane, hem, calibration (hem\n"
               "                   on a calibrated record). Every model is reported beside it.\n"
               "  --threshold T    manual segmentation: L<NN, L>NN, a>NN, b<NN ... (CIE L*a*b*)\n"
               "  --mask FILE      a mask the size of the photo: white = cloth, black = not, grey = decide\n"
               "  --segmentation S auto (default), photo (the single-photo GrabCut segmenter, also on a lab record),\n"
               "                   lab (the lab classifier: disc colour against a floor ring, by chroma or darkness)\n"
               "photo flags (--top, --batch):\n"
               "  --disc D         support disc diameter (mm, cm, m)\n"
               "  --specimen S     specimen: a diameter (300mm) or width x length (300x400mm)\n"
               "  --specimen-angle DEG|auto  rotation of a rectangle (0: width along the photo's x axis; auto: from the outline)\n"
               "  --scale S        disc (default: the disc rim found in the photo), markers (ArUco), chessboard,\n"
               "                   px-per-mm=N (a ruler)\n"
               "  --marker-size L  the markers' black square edge; --marker-dict NAME (default DICT_4X4_50)\n"
               "  --board CxR      chessboard inner corners; --square L (default 25mm)\n"
               "  --reference-height Z  height of the markers / ruler / board above the disc top (negative: below;\n"
               "                   on the floor of a 120 mm stand: -120mm). Default 0.\n"
               "  --scale-from CALIB_PHOTO  find the markers or chessboard once, in a separate photo of the same fixed\n"
               "                   camera at the same pixel size (e.g. the board alone), not in each photo; the output\n"
               "                   names it (\"chessboard ... in CALIB_PHOTO\"). Needs --scale markers or chessboard.\n"
               "  --disc-px X,Y[,R]  the disc's centre (and radius) in the photo [px], when it cannot be found\n"
               "  --camera-height H  optical centre above the disc top; or --focal-px F (the lens in pixels)\n"
               "  --pedestal-height H  the stand's height (default 120mm)\n"
               "  --write-meta FILE  write the meta.json these flags describe (keep it beside the photo)\n"
               "  --table FILE     the batch's table: FILE.csv or FILE.json (rewritten after every photo, so a run\n"
               "                   cut short keeps the rows measured before; a photo that fails is a row with its error)\n"
               "  --manifest M.csv per-photo values for --batch: a header, then a row per photo; columns photo (the file\n"
               "                   name in FOLDER, required), disc_mm, specimen_mm (300 or 300x400), specimen_angle_deg\n"
               "                   (DEG or auto), centre_x_px and centre_y_px (the disc centre, as --disc-px X,Y). An\n"
               "                   empty cell or an unlisted photo takes the command line's value. Checked whole before\n"
               "                   any photo is measured: an unknown column, a photo not in FOLDER or a bad number is an\n"
               "                   error naming the line, column and value (exit 1, no table).\n"
               "Exit codes: 0 measured; 1 refused (the check and what to try are printed) or bad input; 2 bad command\n"
               "line. Files missing from a lab record are listed under not_measured (exit 0); a file the record names\n"
               "that is there but cannot be read (a value out of range, a cell that is not a number, a photo that is\n"
               "not what meta.json says) is listed too, and measure exits 1 after printing the rest.",
               run_measure});

} // namespace cmd_measure
#endif
