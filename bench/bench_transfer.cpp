// bench_transfer: does a preset fitted at one set-up predict the same fabric at
// another? On a folder of records of fabrics tested at several set-ups (the drape
// lab's set-d by default): each set-up fitted alone, every pair fitted jointly and
// all jointly, each preset predicted from flat on every set-up as `drape predict`
// does (3 perturbation seeds, the 95 % interval), scored against the records' D and
// fold count. Writes OUT/transfer.csv, OUT/transfer.md (the table docs/estimate.md
// shows) and OUT/transfer.png, and prints the summary with the load average.
//
//   build/bin/bench_transfer [SET_DIR] [--out DIR] [--fabrics DL-D1,DL-D2] [--modes single,pair,all]
//                            [--held-out-only] [--model M] [--set KEY=VALUE ...] [--seeds N]
//                            [--prior on|off] [--flat-calibration on|off] [--grid N] [--label TEXT]
//                            [--save-presets DIR] [--replay DIR [--laying F] [--perturbation M]]
// [--branch measured|random|mixed] [--fit-laying F] [--fit-perturbation M]: the fit's options.
// --save-presets keeps every fit's preset; --replay predicts presets kept so, fitting
// nothing (laid with --laying / --perturbation [m] instead of their own when given).
#include "bench/transfer.hpp"

#include "engine/cloth/blas_threads.hpp"
#include "engine/core/error.hpp"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

using namespace drape;

namespace {

std::string loadavg()
{
    std::ifstream f("/proc/loadavg");
    std::string a, b, c;
    f >> a >> b >> c;
    return a + " " + b + " " + c;
}

std::vector<std::string> split(const std::string& s)
{
    std::vector<std::string> out;
    std::stringstream ss(s);
    for (std::string x; std::getline(ss, x, ',');)
        if (!x.empty()) out.push_back(x);
    return out;
}

int usage()
{
    std::fprintf(stderr, "usage: bench_transfer [SET_DIR] [--out DIR] [--fabrics F1,F2] [--modes single,pair,all] [--held-out-only] "
                         "[--model M] [--set KEY=VALUE] [--seeds N] [--prior on|off] [--flat-calibration on|off] [--grid N] [--label TEXT] "
                         "[--save-presets DIR] [--replay DIR [--laying F] [--perturbation M]]\n");
    return 2;
}

bool on_off(const std::string& flag, const std::string& v)
{
    if (v == "on") return true;
    if (v == "off") return false;
    throw ParameterError(flag + ": '" + v + "' is not on or off");
}

} // namespace

int main(int argc, char** argv)
{
    std::string dir = DRAPE_SOURCE_DIR "/../shared/data/drape-lab/set-d", out = "transfer-out", label = "bench_transfer";
    bench::TransferOptions o;
    try {
        for (int i = 1; i < argc; ++i) {
            const std::string a = argv[i];
            const bool more = i + 1 < argc;
            if (a == "--out" && more) out = argv[++i];
            else if (a == "--fabrics" && more)
                for (const auto& f : split(argv[++i])) o.fabrics.insert(f);
            else if (a == "--modes" && more) o.modes = split(argv[++i]);
            else if (a == "--held-out-only") o.in_sample = false;
            else if (a == "--model" && more) o.fit.model = estimate::parse_model_variant(argv[++i]);
            else if (a == "--seeds" && more) o.predict.seeds = std::atoi(argv[++i]);
            else if (a == "--grid" && more) o.fit.grid = std::atoi(argv[++i]);
            else if (a == "--label" && more) label = argv[++i];
            else if (a == "--save-presets" && more) o.save_presets = argv[++i];
            else if (a == "--replay" && more) o.replay_presets = argv[++i];
            else if (a == "--laying" && more) o.laying_load = std::atof(argv[++i]);
            else if (a == "--perturbation" && more) o.perturbation_m = std::atof(argv[++i]);
            else if (a == "--flat-calibration" && more) o.fit.flat_calibration = on_off(a, argv[++i]);
            else if (a == "--prior" && more) o.fit.priors = on_off(a, argv[++i]);
            else if (a == "--branch" && more) o.fit.branch = estimate::parse_fold_branch(argv[++i]);
            else if (a == "--fit-laying" && more) o.fit.laying_load = std::atof(argv[++i]);
            else if (a == "--fit-perturbation" && more) o.fit.perturbation_m = std::atof(argv[++i]);
            else if (a == "--set" && more) {
                const std::string kv = argv[++i];
                const auto eq = kv.find('=');
                const cloth::ParamSpec* sp = eq == std::string::npos ? nullptr : cloth::find_param(kv.substr(0, eq));
                if (!sp) throw ParameterError("--set " + kv + ": not KEY=VALUE with a key of the parameter table");
                (*o.fit.start)[sp->id] = std::atof(kv.c_str() + eq + 1);
            } else if (a[0] != '-') dir = a;
            else return usage();
        }
        cloth::single_threaded_blas();
        std::filesystem::create_directories(out);
        const auto records = bench::load_transfer_records(dir);
        std::printf("bench_transfer: %zu records in %s; model %s, grid %d, modes", records.size(), dir.c_str(),
                    estimate::to_string(o.fit.model).c_str(), o.fit.grid);
        for (const auto& m : o.modes) std::printf(" %s", m.c_str());
        std::printf("; %d seeds per prediction; load average %s\n", o.predict.seeds, loadavg().c_str());
        std::fflush(stdout);
        o.log = [](const std::string& s) {
            std::fprintf(stderr, "%s\n", s.c_str());
            std::fflush(stderr);
        };
        const auto t0 = std::chrono::steady_clock::now();
        const auto rows = bench::run_transfer(records, o);
        const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        const auto s = bench::summarise(rows);
        bench::write_transfer_csv(rows, out + "/transfer.csv");
        const std::string md = bench::transfer_markdown(rows, s, "### " + label);
        std::ofstream(out + "/transfer.md") << md;
        bench::write_transfer_plot(rows, out + "/transfer.png");
        std::printf("%s\n", md.c_str());
        std::printf("wall %.0f s; load average %s; written %s/transfer.{csv,md,png}\n", wall, loadavg().c_str(), out.c_str());
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_transfer: %s\n", e.what());
        return 1;
    }
    return 0;
}
