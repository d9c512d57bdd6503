// The fit's drapes from flat (Evaluator::draw_from_flat): the preset at a point
// draped from a flat, wavy start as drape predict drapes it, on the fit's grid and
// on the flat check's finer one, with a memo of the drapes already drawn at the
// same point (docs/decisions/0018-flat-check-grid-61.md).
#include "engine/estimate/detail/evaluator.hpp"

#include "engine/core/parallel.hpp"

#include <algorithm>
#include <cmath>

namespace drape::estimate::detail {

using cloth::Param;

DrapeFeatures Evaluator::drape_cold(int r, const cloth::FabricParams& p, std::uint64_t seed, bool on_branch, int grid, bool* at_rest,
                                    const cloth::LevelRest* start, std::vector<cloth::LevelRest>* levels) const
{
    if (m_opt.cancel && m_opt.cancel->load()) throw CancelledFit{};
    cloth::RestOptions ro = m_opt.rest;
    ro.cancel = m_opt.cancel;
    ro.progress = nullptr;
    const MeasuredDrape& rec = m_recs[static_cast<std::size_t>(r)];
    cloth::DrapeSetup setup = setup_for(r, seed, on_branch);
    if (grid > 0) setup.grid = grid;
    const cloth::DrapeResult sim = cloth::simulate_drape(params_for_record(p, rec), setup, ro, m_opt.model_options, start, levels);
    if (m_opt.cancel && m_opt.cancel->load()) throw CancelledFit{};
    if (at_rest) *at_rest = sim.status.converged();
    return drape_features(sim, rec);
}

void Evaluator::draw_from_flat(const Eigen::VectorXd& x, Stage stage, FlatDraw which)
{
    announce(stage);
    draw_flat(x, which);
    report(stage);
}

void Evaluator::draw_flat(const Eigen::VectorXd& x, FlatDraw which)
{
    const bool fine_too = which != FlatDraw::FitGrid;
    const cloth::FabricParams p = params_at(x);
    const int R = static_cast<int>(m_recs.size());
    m_cold.resize(static_cast<std::size_t>(R));
    m_cold_seeds.resize(static_cast<std::size_t>(R), 0);
    m_cold_nodes.resize(static_cast<std::size_t>(R));
    m_cold_fine.assign(static_cast<std::size_t>(R), std::nullopt); // another point's
    struct Job {
        int r;
        std::uint64_t seed;
        int grid; // 0: the fit's; or flat_check_grid
        const FlatMemo* kept = nullptr;        // drawn before at p
        const cloth::LevelRest* start = nullptr; // the finer drape's coarse level, from a kept drape
    };
    auto kept_drape = [&](int r, std::uint64_t seed, int grid) -> const FlatMemo* {
        for (const auto& m : m_flat_memo)
            if (m.r == r && m.seed == seed && m.grid == grid && m.p.values == p.values) return &m;
        return nullptr;
    };
    // A kept level rest of record r's drapes with `seed` at p on `grid`.
    auto kept_level = [&](int r, std::uint64_t seed, int grid) -> const cloth::LevelRest* {
        for (const auto& m : m_flat_memo)
            if (m.r == r && m.seed == seed && m.p.values == p.values)
                for (const auto& l : m.levels)
                    if (l.grid == grid) return &l;
        return nullptr;
    };
    std::vector<Job> jobs;
    // The finer grid's drapes first: each is the longest job (it lays the sheet
    // on the continuation's coarsest level, then refines), so the two threads
    // finish together.
    const bool finer_drapes = m_opt.flat_check_grid > m_opt.grid && m_opt.random_start_seeds > 0; // in this fit (not only this call)
    const bool fine = fine_too && finer_drapes;
    const int fine_level = cloth::continuation_level(m_opt.flat_check_grid); // 0: the finer drape has none
    // Every record's (a record fitted from the random mix has its cold_* from
    // the spread's draws, but no drape on the finer grid).
    for (int r = 0; r < R && fine; ++r) {
        const std::uint64_t seed = m_opt.seed + 1000;
        jobs.push_back({r, seed, m_opt.flat_check_grid, kept_drape(r, seed, m_opt.flat_check_grid), fine_level > 0 ? kept_level(r, seed, fine_level) : nullptr});
    }
    for (int r = 0; r < R; ++r)
        if (branch_of(r) != 0)
            for (int k = 0; k < m_opt.random_start_seeds; ++k) {
                const std::uint64_t seed = m_opt.seed + 1000 + static_cast<std::uint64_t>(k);
                jobs.push_back({r, seed, 0, kept_drape(r, seed, 0), nullptr});
            }
    if (jobs.empty()) return;
    // Those drawn before first in the list (no work), then the finer ones that
    // start from a kept level (the shortest of the finer ones) last among them.
    std::vector<FlatMemo> drawn(jobs.size());
    std::vector<std::size_t> todo;
    for (std::size_t j = 0; j < jobs.size(); ++j)
        if (jobs[j].kept) drawn[j] = *jobs[j].kept;
        else todo.push_back(j);
    std::stable_partition(todo.begin(), todo.end(), [&](std::size_t j) { return !jobs[j].start; });
    const auto t0 = Clock::now();
    const int nthreads = std::clamp(m_opt.parallel_seeds, 1, std::max(1, static_cast<int>(todo.size())));
    parallel_for(todo.size(), nthreads, [&](std::size_t t) {
        const std::size_t j = todo[t];
        const Job& job = jobs[j];
        FlatMemo& m = drawn[j];
        m.p = p;
        m.r = job.r;
        m.seed = job.seed;
        m.grid = job.grid;
        bool ok = false;
        m.drape.features = drape_cold(job.r, p, job.seed, false, job.grid, &ok, job.start, &m.levels);
        m.drape.at_rest = ok;
    });
    if (!todo.empty()) m_work.simulation_seconds += std::chrono::duration<double>(Clock::now() - t0).count() * nthreads;
    m_work.simulations += static_cast<long>(todo.size());
    for (int r = 0; r < R; ++r) {
        std::vector<DrapeFeatures> cold;
        for (std::size_t j = 0; j < jobs.size(); ++j) {
            if (jobs[j].r != r) continue;
            if (jobs[j].grid > 0) m_cold_fine[static_cast<std::size_t>(r)] = drawn[j].drape;
            else cold.push_back(drawn[j].drape.features);
        }
        if (cold.empty()) continue;
        std::vector<double> closed;
        m_cold[static_cast<std::size_t>(r)] = average_features(cold, &closed);
        m_cold_seeds[static_cast<std::size_t>(r)] = static_cast<int>(cold.size());
        m_cold_nodes[static_cast<std::size_t>(r)].clear();
        for (const auto& c : cold) m_cold_nodes[static_cast<std::size_t>(r)].push_back(c.node_count);
    }
    // Keep this point's new drapes (the kept ones stay), dropping the oldest
    // points' beyond kFlatMemoPoints; of their level rests only the one a finer
    // drape starts from (its seed's, on the finer grid's coarse level).
    for (std::size_t j : todo) {
        FlatMemo& m = drawn[j];
        std::erase_if(m.levels, [&](const cloth::LevelRest& l) { return !finer_drapes || m.seed != m_opt.seed + 1000 || l.grid != fine_level; });
        m_flat_memo.push_back(std::move(m));
    }
    for (const Job& job : jobs)
        if (job.start && !job.kept) ++m_flat_levels_reused;
    std::vector<cloth::FabricParams> points;
    for (auto it = m_flat_memo.rbegin(); it != m_flat_memo.rend(); ++it)
        if (std::none_of(points.begin(), points.end(), [&](const cloth::FabricParams& q) { return q.values == it->p.values; })) points.push_back(it->p);
    if (points.size() > kFlatMemoPoints) {
        points.resize(kFlatMemoPoints);
        std::erase_if(m_flat_memo, [&](const FlatMemo& m) {
            return std::none_of(points.begin(), points.end(), [&](const cloth::FabricParams& q) { return q.values == m.p.values; });
        });
    }
}

} // namespace drape::estimate::detail
