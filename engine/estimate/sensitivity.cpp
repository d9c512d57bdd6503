#include "engine/estimate/sensitivity.hpp"

#include "engine/estimate/plot.hpp"

#include "engine/cloth/blas_threads.hpp"
#include "engine/core/error.hpp"
#include "engine/core/io.hpp"
#include "engine/core/parallel.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <mutex>
#include <sstream>

namespace drape::estimate {

using cloth::Param;

std::vector<SensitivityRow> sensitivity_study(const cloth::FabricParams& base, const SensitivityOptions& opt)
{
    if (opt.steps < 2 || opt.steps > 41) throw ParameterError("sensitivity: steps = " + std::to_string(opt.steps) + " is outside [2, 41]");
    if (!(opt.span_decades > 0) || opt.span_decades > 4)
        throw ParameterError("sensitivity: span = " + std::to_string(opt.span_decades) + " decades is outside (0, 4]");
    base.validate("sensitivity: base fabric");
    opt.setup.validate();
    cloth::single_threaded_blas();
    std::vector<SensitivityRow> rows;
    for (Param p : opt.params) {
        const auto& sp = cloth::spec(p);
        for (int i = 0; i < opt.steps; ++i) {
            const double t = -1.0 + 2.0 * i / (opt.steps - 1);
            SensitivityRow r;
            r.param = p;
            if (sp.log_scale && base[p] > 0) {
                r.value = std::clamp(base[p] * std::pow(10.0, t * opt.span_decades), sp.lower, sp.upper);
            } else {
                r.value = std::clamp(base[p] + t * 0.5 * (sp.upper - sp.lower), sp.lower, sp.upper);
            }
            r.factor = base[p] != 0 ? r.value / base[p] : 0;
            rows.push_back(r);
        }
    }
    std::mutex mu;
    int done = 0;
    parallel_for(
        rows.size(), opt.threads,
        [&](std::size_t j) {
            SensitivityRow& r = rows[j];
            cloth::FabricParams p = base;
            p[r.param] = r.value;
            cloth::RestOptions ro;
            ro.cancel = opt.cancel;
            const cloth::DrapeResult d = cloth::simulate_drape(p, opt.setup, ro, opt.model);
            r.drape_coefficient_percent = d.metrics.drape_coefficient_percent;
            r.node_count = d.metrics.node_count;
            r.hem_min_z = d.hem.min_z;
            r.converged = d.status.converged();
            for (int k = 1; k <= opt.harmonics; ++k)
                r.harmonic_magnitudes_m.push_back(k <= d.metrics.fourier.harmonics() ? d.metrics.fourier.magnitude(k) : 0.0);
            std::lock_guard lk(mu);
            ++done;
            if (opt.progress) opt.progress(done, static_cast<int>(rows.size()));
        },
        [&] { return opt.cancel && opt.cancel->load(); });
    return rows;
}

std::vector<std::string> write_sensitivity(const std::vector<SensitivityRow>& rows, const cloth::FabricParams& base,
                                           const std::string& dir)
{
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) throw FileError(dir + ": cannot create the folder (" + ec.message() + ")");
    std::vector<std::string> files;
    std::ostringstream csv;
    csv.precision(10);
    int K = 0;
    for (const auto& r : rows) K = std::max(K, static_cast<int>(r.harmonic_magnitudes_m.size()));
    csv << "parameter,unit,value,factor,drape_coefficient_percent,node_count,hem_min_z_m,converged";
    for (int k = 1; k <= K; ++k) csv << ",harmonic_" << k << "_m";
    csv << "\n";
    for (const auto& r : rows) {
        csv << cloth::spec(r.param).key << "," << cloth::spec(r.param).unit << "," << r.value << "," << r.factor << ","
            << r.drape_coefficient_percent << "," << r.node_count << "," << r.hem_min_z << "," << (r.converged ? 1 : 0);
        for (int k = 0; k < K; ++k) csv << "," << (k < static_cast<int>(r.harmonic_magnitudes_m.size()) ? r.harmonic_magnitudes_m[k] : 0.0);
        csv << "\n";
    }
    drape::write_file_atomic((std::filesystem::path(dir) / "sensitivity.csv").string(), csv.str());
    files.push_back("sensitivity.csv");
    std::vector<Param> params;
    for (const auto& r : rows)
        if (std::find(params.begin(), params.end(), r.param) == params.end()) params.push_back(r.param);
    for (Param p : params) {
        const auto& sp = cloth::spec(p);
        const bool lg = sp.log_scale && base[p] > 0;
        std::vector<double> x, dc, nodes;
        std::vector<std::vector<double>> h(K);
        for (const auto& r : rows) {
            if (r.param != p) continue;
            x.push_back(lg ? std::log10(r.value) : r.value);
            dc.push_back(r.drape_coefficient_percent);
            nodes.push_back(r.node_count);
            for (int k = 0; k < K; ++k) h[k].push_back(k < static_cast<int>(r.harmonic_magnitudes_m.size()) ? r.harmonic_magnitudes_m[k] * 1e3 : 0.0);
        }
        const std::string xl = (lg ? "log10 " : "") + std::string(sp.key) + " [" + std::string(sp.unit) + "]";
        {
            Plot pl(700, 420, std::string(sp.key) + ": drape coefficient and node count (x10)", xl, "D [%] / nodes x 10");
            pl.line(x, dc, {30, 90, 200}, "drape coefficient [%]", 2);
            pl.points(x, dc, {30, 90, 200});
            std::vector<double> n10;
            for (double v : nodes) n10.push_back(10 * v);
            pl.line(x, n10, {210, 80, 30}, "node count x 10", 2, true);
            pl.points(x, n10, {210, 80, 30});
            pl.set_caption("one parameter varied at a time around the preset (others fixed); preset value in the middle");
            const std::string f = std::string(sp.key) + "_dc_nodes.png";
            pl.save((std::filesystem::path(dir) / f).string());
            files.push_back(f);
        }
        {
            Plot pl(700, 420, std::string(sp.key) + ": shadow-outline harmonic magnitudes", xl, "|c_k| [mm]");
            for (int k = 0; k < K; ++k) pl.line(x, h[k], category(k), "k = " + std::to_string(k + 1), 2);
            pl.set_caption("fold pattern: the dominant k is the node count; k = 2 is the warp/weft ellipse");
            const std::string f = std::string(sp.key) + "_harmonics.png";
            pl.save((std::filesystem::path(dir) / f).string());
            files.push_back(f);
        }
    }
    return files;
}

} // namespace drape::estimate
