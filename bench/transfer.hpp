#pragma once
// The transfer study: does a preset fitted at some set-ups predict the same
// fabric at the others? For every fabric with records at several set-ups
// (folders named <fabric>-<D1>-<D2>, e.g. DL-D1-240-180): each set-up fitted
// alone, every pair fitted jointly, all of them jointly (the model's ceiling),
// and each preset predicted from flat on every set-up of its fabric exactly as
// `drape predict` does (estimate::predict_drape). Shared by bench_transfer and
// the slow regression test.
#include "engine/estimate/fit.hpp"
#include "engine/estimate/predict.hpp"

#include <functional>
#include <set>
#include <string>
#include <vector>

namespace drape::bench {

struct TransferRecord {
    estimate::MeasuredDrape record;
    std::string fabric; ///< the record id without its trailing "-<D1>-<D2>"
    std::string setup;  ///< "240/180"
};

/// Every record folder under `dir` (sorted), grouped by fabric; fabrics with a
/// single set-up are kept (they have nothing to predict but the ceiling).
std::vector<TransferRecord> load_transfer_records(const std::string& dir);

/// A fit's subsets: "single" (each set-up alone), "pair" (every two), "all".
struct TransferOptions {
    std::vector<std::string> modes = {"single", "pair", "all"};
    std::set<std::string> fabrics;       ///< empty: every fabric with two set-ups or more
    bool in_sample = true;               ///< also predict the fitted set-ups (from flat)
    estimate::FitOptions fit = estimate::drape_fit_defaults();
    estimate::PredictOptions predict;
    std::function<void(const std::string&)> log; ///< one line per fit / prediction
    /// Non-empty: each fit's preset is written there as <fabric>_<fitted>.json
    /// (the set-ups joined by '+', '/' as '-').
    std::string save_presets;
    /// Non-empty: no fits - the presets are read from there (as save_presets
    /// wrote them) and only predicted, e.g. with another laying (overrides below).
    std::string replay_presets;
    /// Overrides of how the presets are laid when predicted (< 0: the preset's own).
    double laying_load = -1, perturbation_m = -1;
};

struct TransferRow {
    std::string fabric, mode, fitted, target; ///< fitted: "300/150" or "240/180+360/180"
    bool held_out = true;                     ///< target not among the fitted set-ups
    double d_lab = 0;                         ///< the record's D (the lab's drapemeter) [%]
    int n_lab = -1;                           ///< the record's fold count (top photo)
    estimate::Prediction prediction;          ///< drapes from flat of the preset on the target
    double fit_seconds = 0;                   ///< of the fit that made the preset
    double chi2 = 0;
    int dof = 0;
    double warp_weft_ratio = 1;
    std::string fit_notes;                    ///< parameters at a fit bound, prior-decided, tied, held
    double d_error() const { return prediction.dc_percent - d_lab; }
    int n_error() const { return n_lab >= 0 ? prediction.node_count - n_lab : 0; }
    bool inside() const { return d_lab >= prediction.dc_lower95 && d_lab <= prediction.dc_upper95; }
};

std::vector<TransferRow> run_transfer(const std::vector<TransferRecord>& records, const TransferOptions& options);

/// The done-when numbers of the transfer issue over `rows`.
struct TransferSummary {
    int single_n = 0, single_ok = 0;  ///< held-out predictions of single-set-up fits; within 3 points and 1 fold
    double single_max_abs = 0, single_mean_abs = 0;
    int single_beyond6 = 0;
    int pair_n = 0, pair_ok = 0;      ///< held-out predictions of pair fits; within 2 points and 1 fold
    double pair_max_abs = 0, pair_mean_abs = 0;
    int all_n = 0, all_ok = 0;        ///< the joint fits of every set-up, in sample, within 2 points and 1 fold
    int interval_n = 0, interval_in = 0; ///< held-out predictions whose 95 % interval holds the record's D
    double fit_seconds_max_single = 0, fit_seconds_max_pair = 0, fit_seconds_max_all = 0;
    int ratio_beyond3 = 0;            ///< fits whose warp/weft bending ratio is beyond 3
};
TransferSummary summarise(const std::vector<TransferRow>& rows);

void write_transfer_csv(const std::vector<TransferRow>& rows, const std::string& path);
/// The table and the summary as markdown (docs/estimate.md includes it).
std::string transfer_markdown(const std::vector<TransferRow>& rows, const TransferSummary& s, const std::string& heading);
/// Predicted against measured D with the 95 % intervals, held-out predictions by mode.
void write_transfer_plot(const std::vector<TransferRow>& rows, const std::string& path);

} // namespace drape::bench
