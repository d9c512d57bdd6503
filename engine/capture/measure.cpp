#include "engine/capture/measure.hpp"

#include "engine/capture/image.hpp"
#include "engine/capture/steps.hpp"
#include "engine/cloth/elastica.hpp"
#include "engine/core/error.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace drape::capture {

using namespace detail;

PedestalWidth measure_pedestal_width(const record::Record& rec)
{
    Measurement out;
    out.side.pedestal.declared = 2 * rec.R2;
    if (!rec.has_camera("side") || !std::filesystem::exists(rec.file(rec.cameras.at("side").image))) return out.side.pedestal;
    try {
        out.side_image = load_image(rec, "side");
    } catch (const Error&) {
        return out.side.pedestal;
    }
    measure_pedestal(rec, out);
    return out.side.pedestal;
}

Measurement measure_record(const record::Record& rec, const MeasureOptions& opt)
{
    Measurement out;
    out.specimen_id = rec.specimen_id;
    out.lab_dc_percent = rec.lab_drape_coefficient_percent;
    for (const auto& k : rec.unknown_fields) out.warnings.push_back("meta.json: unknown field '" + k + "' kept, not used");

    std::optional<record::ContourStack> stack;
    if (std::filesystem::exists(rec.file(rec.contours_file))) {
        try {
            stack = record::read_contours(rec);
        } catch (const Error& e) {
            out.not_measured.push_back(std::string("laser contours: ") + e.what());
            // A file without rows (a lab without a profiler, or one that cut no
            // depth) holds no contours: not measured, not bad input.
            if (!record::no_contour_rows(rec.file(rec.contours_file))) out.bad_files.push_back(e.what());
        }
        if (stack) try {
            measure_contours(rec, *stack, out);
        } catch (const Error& e) {
            out.not_measured.push_back(std::string("laser contours: ") + e.what());
            stack.reset();
        }
    } else {
        out.not_measured.push_back("laser contours: " + rec.contours_file + " not in the record");
    }

    auto load = [&](const std::string& station, cv::Mat& img) {
        if (!rec.has_camera(station)) {
            out.not_measured.push_back(station + " view: no 'cameras." + station + "' in meta.json");
            return false;
        }
        if (!std::filesystem::exists(rec.file(rec.cameras.at(station).image))) {
            out.not_measured.push_back(station + " view: " + rec.cameras.at(station).image + " not in the record");
            return false;
        }
        try {
            img = load_image(rec, station);
            return true;
        } catch (const Error& e) {
            out.not_measured.push_back(station + " view: " + e.what());
            out.bad_files.push_back(e.what());
            return false;
        }
    };

    bool have_top = false;
    if (rec.top_photo) {
        try {
            out.top_image = load_photo(rec, rec.top_photo->image);
            have_top = true;
        } catch (const Error& e) {
            out.not_measured.push_back(std::string("top view: ") + e.what());
            std::error_code ec;
            if (std::filesystem::exists(rec.dir / rec.top_photo->image, ec)) out.bad_files.push_back(e.what());
        }
    } else {
        have_top = load("top", out.top_image);
    }
    if (have_top) {
        try {
            measure_top(rec, opt, stack ? &*stack : nullptr, out);
        } catch (const RefusalError& e) {
            out.refused = e.refusal;
            out.top.measured = false;
            out.not_measured.push_back("top view: refused (" + e.refusal.check + "): " + e.refusal.message);
        }
    }
    if (!out.top.measured)
        out.not_measured.push_back("drape coefficient and nodes: need a usable top view");
    if (load("side", out.side_image)) {
        measure_pedestal(rec, out);
        if (out.top.measured)
            measure_side(rec, out);
        else
            out.not_measured.push_back("side view: hem height needs the top view's outline");
    }
    if (rec.has_camera("iso"))
        out.not_measured.push_back(
            std::filesystem::exists(rec.file(rec.cameras.at("iso").image))
                ? "iso view: not analysed by this version (for a person checking the drape)"
                : "iso view: " + rec.cameras.at("iso").image + " not in the record");

    if (out.top.measured) {
        // Height error of the model: what the side view measured where it can
        // see the hem, never less than 3 mm; 10 mm when there is no side view.
        const double dz = out.side.measured ? std::max(out.side.model_rms_diff, 0.003) : 0.010;
        set_hem_depth_error(out.top, dz);
    }

    // Lowest hem point: the lowest of the evidence. The top view's height
    // model covers every angle; the side view sees the front hem directly.
    if (out.top.measured && !out.top.outline_z.empty() && out.top.perspective == "hem") {
        out.hem_min_height = *std::min_element(out.top.outline_z.begin(), out.top.outline_z.end());
        out.hem_min_source = std::string("top-view silhouette back-projected with the height model (") +
                             to_string(out.top.height_model) + ")";
    }
    if (out.side.measured && (!out.hem_min_height || out.side.hem_min_z < *out.hem_min_height)) {
        out.hem_min_height = out.side.hem_min_z;
        out.hem_min_source = "side-view silhouette against the pedestal";
    }
    if (!out.hem_min_height && stack && !stack->depths.empty()) {
        // Only a bound: the hem is at least as deep as the deepest closed cut.
        out.hem_min_height = -*std::max_element(stack->depths.begin(), stack->depths.end());
        out.hem_min_source = "deepest closed laser contour (upper bound: the hem is lower still)";
    }
    if (!out.hem_min_height) out.not_measured.push_back("hem height: needs the top view, side view or contours");
    // What D says about bending, whatever the folds do: the bending whose free
    // radial strips drape to it (a round specimen of declared weight).
    if (out.top.measured && !out.refused && rec.areal_density && rec.specimen.shape == record::Specimen::Shape::Round) {
        const double dc = out.top.metrics.drape_coefficient_percent;
        if (dc > 0 && dc < 100)
            out.free_strip_bending_bound = cloth::free_strip_bending_bound(2 * rec.R1, 2 * rec.R2, *rec.areal_density, dc);
    }
    for (const auto& w : out.top.warnings) out.warnings.push_back(w);
    for (const auto& w : out.side.warnings) out.warnings.push_back(w);
    return out;
}

} // namespace drape::capture
