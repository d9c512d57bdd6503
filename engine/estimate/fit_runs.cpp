// A fit of several runs (the grid refinement's, the bending tie's): each run's
// progress continues the ones before it, their work is added and their traces
// joined in the order they ran.
#include "engine/estimate/detail/pipeline.hpp"

#include <utility>

namespace drape::estimate::detail {

std::function<void(const FitProgress&)> continued_progress(const FitOptions& options, std::string prefix, const FitResult& before, bool search)
{
    if (!options.progress) return nullptr;
    const int evals = before.evaluations;
    const long sims = before.simulations;
    const double secs = before.wall_seconds;
    return [&options, prefix = std::move(prefix), evals, sims, secs, search](const FitProgress& p) {
        FitProgress q = p;
        q.search = search && p.search;
        q.stage = prefix + p.stage;
        q.evaluation += evals;
        q.planned += evals;
        q.simulations += sims;
        q.elapsed_s += secs;
        options.progress(q);
    };
}


FitResult combine_runs(const FitResult& first, const FitResult& second, bool keep_second, const std::string& prefix)
{
    FitResult kept = keep_second ? second : first;
    kept.options.progress = nullptr;
    kept += static_cast<const WorkCounters&>(keep_second ? first : second);
    std::vector<FitTraceEntry> t = first.trace;
    const int offset = t.empty() ? 0 : t.back().evaluation;
    const double t_off = t.empty() ? 0.0 : t.back().elapsed_s;
    for (auto e : second.trace) {
        e.evaluation += offset;
        e.elapsed_s += t_off;
        e.stage = prefix + e.stage;
        t.push_back(std::move(e));
    }
    kept.trace = std::move(t);
    kept.cancelled = kept.cancelled || second.cancelled; // a cancelled second fit keeps the first, but the run was stopped
    return kept;
}

void record_work(FitResult& out, const Evaluator& ev, Clock::time_point t0)
{
    static_cast<WorkCounters&>(out) = ev.work();
    out.trace = ev.trace();
    out.wall_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
}

} // namespace drape::estimate::detail
