// `drape measure RECORD_DIR`: a drape-lab record -> calibrated measurements.
#include "cli/command.hpp"
#include "cli/progress.hpp"

#ifdef HAVE_DRAPE_CAPTURE
#include "engine/capture/export.hpp"
#include "engine/capture/measure.hpp"
#include "engine/capture/report.hpp"
#include "engine/core/error.hpp"

#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <filesystem>
#include <cstdio>
#include <iostream>

namespace {

int run_measure(const std::vector<std::string>& argv)
{
    using namespace drape;
    cli::Args a(argv, {"--overlay", "--rays", "--node-prominence", "--texture", "--mesh"}, {"--json", "--no-calibrate"});
    if (a.positionals().size() != 1) throw cli::UsageError("expected exactly one RECORD_DIR");
    const record::Record rec = record::read_record(a.positionals()[0]);
    capture::MeasureOptions opt;
    opt.rays = a.get_int("--rays", 720, 90, 7200);
    opt.calibrate = !a.has("--no-calibrate");
    opt.metrics.relative_prominence = a.get_double("--node-prominence", opt.metrics.relative_prominence);
    if (!(opt.metrics.relative_prominence >= 0 && opt.metrics.relative_prominence < 1))
        throw cli::UsageError("--node-prominence must be in [0, 1)");
    // One measurement is one step (a second or two): a line when it starts and one when it is done.
    cli::Progress progress("measure " + rec.specimen_id, a.has("--json"));
    progress.update(-1, "photos, calibration, contours");
    const capture::Measurement m = capture::measure_record(rec, opt);
    progress.finish();
    if (auto path = a.get("--overlay")) {
        if (m.top_image.empty()) throw FileError(*path + ": no overlay: the record has no readable top photo");
        if (!cv::imwrite(*path, capture::draw_top_overlay(rec, m))) throw FileError(*path + ": cannot write the overlay");
    }
    if (auto path = a.get("--texture")) {
        const cv::Mat tex = capture::rectified_texture(rec, m);
        if (!cv::imwrite(*path, tex)) throw FileError(*path + ": cannot write the texture");
        std::filesystem::path p(*path);
        if (p.extension() == ".bmp") cv::imwrite(p.replace_extension(".png").string(), tex);
    }
    if (auto path = a.get("--mesh")) capture::write_obj(capture::contour_surface(rec, m), *path);
    if (a.has("--json")) {
        std::cout << capture::to_json(m).dump(1) << "\n";
        return 0;
    }
    std::printf("record %s\n", m.specimen_id.c_str());
    if (m.top.measured) {
        const auto& t = m.top.metrics;
        std::printf("  drape coefficient  %.1f %% (+- %.1f, height model: %s)", t.drape_coefficient_percent,
                    m.top.dc_uncertainty_percent, capture::to_string(m.top.height_model));
        if (m.lab_dc_percent) std::printf("   lab %.1f %%", *m.lab_dc_percent);
        std::printf("\n  uncorrected (z=0)  %.1f %%   chord model %.1f %%\n", m.top.dc_plane_percent, m.top.dc_chord_percent);
        std::printf("  nodes              %d at", t.node_count);
        for (double th : t.node_angles_rad) std::printf(" %.0f", th * 180 / M_PI);
        std::printf(" deg\n  radius mean/min/max %.1f / %.1f / %.1f mm\n", t.mean_radius_m * 1e3, t.min_radius_m * 1e3,
                    t.max_radius_m * 1e3);
    }
    if (m.hem_min_height)
        std::printf("  lowest hem         z = %.1f mm (%s)\n", *m.hem_min_height * 1e3, m.hem_min_source.c_str());
    if (m.top_calibration && m.top_calibration->ok)
        std::printf("  top camera         %zu boards, reprojection %.2f px, declared pose off by %.2f px\n",
                    m.top_calibration->boards_found.size(), m.top_calibration->rms_px_measured,
                    m.top_calibration->max_shift_px);
    for (const auto& c : m.contours) {
        std::printf("  contour %4.0f mm    mean r %.1f mm, %d harmonics, fit RMS %.2f mm (noise %.2f mm), |c1..c4| =",
                    c.depth * 1e3, c.mean_radius * 1e3, c.harmonics, c.residual_rms * 1e3, c.noise_sigma * 1e3);
        for (int k = 1; k <= std::min(4, c.harmonics); ++k) std::printf(" %.1f", c.fit.magnitude(k) * 1e3);
        std::printf(" mm\n");
    }
    for (const auto& s : m.not_measured) std::printf("  not measured: %s\n", s.c_str());
    for (const auto& s : m.warnings) std::printf("  warning: %s\n", s.c_str());
    return 0;
}

DRAPE_COMMAND({"measure", "measure a drape-lab record (photos, laser contours)",
               "usage: drape measure RECORD_DIR [--json] [--overlay out.png] [--texture F.bmp] [--mesh F.obj]\n                    [--rays N] [--no-calibrate] [--node-prominence F]\n"
               "  RECORD_DIR       folder with meta.json and any of top.jpg, side.jpg, iso.jpg, contours.csv\n"
               "  --json           print the measurements as JSON (SI units, unit in each key)\n"
               "  --overlay FILE   write the top photo with the traced outline, nodes and pedestal circle\n"
               "  --texture FILE   write the top view rectified to the pedestal-top plane, 0.25 mm/px\n"
               "                   (FILE.bmp also writes FILE.png)\n"
               "  --mesh FILE.obj  write the surface through the contour levels' Fourier series [m]\n"
               "  --rays N         rays traced around the axis (default 720)\n"
               "  --no-calibrate   use the declared top pose instead of solvePnP on the floor chessboards\n"
               "  --node-prominence F  a fold crest must rise F x (max r - min r) above its troughs (default 0.10)\n"
               "Files that are missing or unreadable are listed under not_measured; a bad meta.json is an error.",
               run_measure});

} // namespace
#endif
