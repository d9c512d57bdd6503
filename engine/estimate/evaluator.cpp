#include "engine/estimate/evaluator.hpp"

#include "engine/core/parallel.hpp"

#include <algorithm>
#include <mutex>

namespace drape::estimate::detail {

using cloth::Param;

Evaluator::Evaluator(const std::vector<MeasuredDrape>& recs, const FitOptions& opt, std::vector<FitVariable> vars,
                     cloth::FabricParams base)
    : m_recs(recs), m_opt(opt), m_vars(std::move(vars)), m_base(base), m_t0(Clock::now())
{
    // Both sides of a residual are one draw of the fold pattern: the record
    // (one drape) and the mean of S simulated seeds. The variance of the
    // difference is floor^2 (1 + 1/S).
    m_noise = opt.noise;
    const double f = std::sqrt(1.0 + 1.0 / std::max(1, opt.seeds_per_evaluation));
    m_noise.dc_seed_percent *= f;
    m_noise.nodes *= f;
    m_noise.radius_seed_m *= f;
    m_noise.fold_seed_m *= f;
    m_noise.axis_seed_m *= f;
    for (const auto& r : recs) m_meas.push_back(drape_features(r));
}

cloth::DrapeSetup Evaluator::setup_for(int r, std::uint64_t seed, bool on_branch) const
{
    const cloth::DrapeSetup s = m_recs[static_cast<std::size_t>(r)].setup(m_opt.grid, seed);
    const int n = on_branch ? branch_of(r) : 0;
    return n > 0 ? cloth::on_fold_branch(s, n, m_opt.branch_lift_m) : s;
}

int Evaluator::branch_of(int r) const
{
    return m_opt.branch == FoldBranch::Measured ? measured_fold_branch(m_meas[static_cast<std::size_t>(r)].node_count) : 0;
}

cloth::FabricParams Evaluator::params_at(const Eigen::VectorXd& x) const
{
    cloth::FabricParams p = m_base;
    for (std::size_t i = 0; i < m_vars.size(); ++i)
        for (Param q : m_vars[i].params)
            p[q] = std::clamp(m_vars[i].to_value(x[static_cast<Eigen::Index>(i)]), cloth::spec(q).lower, cloth::spec(q).upper);
    return p;
}

Evaluation Evaluator::evaluate(const Eigen::VectorXd& x, Start from)
{
    if (m_opt.cancel && m_opt.cancel->load()) throw CancelledFit{};
    const cloth::FabricParams p = params_at(x);
    const int S = std::max(1, m_opt.seeds_per_evaluation);
    const int R = static_cast<int>(m_recs.size());
    Evaluation e;
    e.sims.assign(static_cast<std::size_t>(R), std::vector<cloth::DrapeResult>(static_cast<std::size_t>(S)));
    const auto t0 = Clock::now();
    const int nthreads = std::clamp(m_opt.parallel_seeds, 1, R * S);
    parallel_for(static_cast<std::size_t>(R * S), nthreads, [&](std::size_t j) {
        const int r = static_cast<int>(j) / S, s = static_cast<int>(j) % S;
        const cloth::DrapeSetup setup = setup_for(r, m_opt.seed + static_cast<std::uint64_t>(s), true);
        const cloth::FabricParams pr = params_for_record(p, m_recs[static_cast<std::size_t>(r)]);
        cloth::RestOptions ro = m_opt.rest;
        ro.cancel = m_opt.cancel;
        ro.progress = nullptr;
        auto& out = e.sims[static_cast<std::size_t>(r)][static_cast<std::size_t>(s)];
        if (from == Start::Best && m_have_states)
            out = cloth::simulate_drape_from(pr, setup, m_states[static_cast<std::size_t>(r)][static_cast<std::size_t>(s)], ro,
                                             m_opt.model_options);
        else
            out = cloth::simulate_drape(pr, setup, ro, m_opt.model_options);
    });
    m_sim_seconds += std::chrono::duration<double>(Clock::now() - t0).count() * nthreads;
    m_simulations += static_cast<long>(R * S);
    if (m_opt.cancel && m_opt.cancel->load()) throw CancelledFit{};

    for (int r = 0; r < R; ++r) {
        std::vector<DrapeFeatures> fs;
        for (int s = 0; s < S; ++s) {
            const auto& sim = e.sims[static_cast<std::size_t>(r)][static_cast<std::size_t>(s)];
            if (!sim.status.converged()) ++m_unconverged;
            fs.push_back(drape_features(sim, m_recs[static_cast<std::size_t>(r)]));
        }
        std::vector<double> closed;
        DrapeFeatures avg = average_features(fs, &closed);
        auto t = residual_terms(r, m_meas[static_cast<std::size_t>(r)], avg, closed, m_noise);
        for (auto& term : t)
            term.fitted = std::find(m_opt.channels.begin(), m_opt.channels.end(), channel_of(term.kind)) != m_opt.channels.end();
        e.terms.insert(e.terms.end(), t.begin(), t.end());
        e.features.push_back(std::move(avg));
    }
    if (m_sigma_floor.size() == e.terms.size())
        for (std::size_t i = 0; i < e.terms.size(); ++i) e.terms[i].sigma = std::max(e.terms[i].sigma, m_sigma_floor[i]);
    e.chi2 = chi_square(e.terms);
    ++m_evaluations;
    m_last = e;
    m_last_x = x;
    return e;
}

DrapeFeatures Evaluator::drape_cold(int r, const cloth::FabricParams& p, std::uint64_t seed, bool on_branch)
{
    if (m_opt.cancel && m_opt.cancel->load()) throw CancelledFit{};
    cloth::RestOptions ro = m_opt.rest;
    ro.cancel = m_opt.cancel;
    ro.progress = nullptr;
    const auto t0 = Clock::now();
    const MeasuredDrape& rec = m_recs[static_cast<std::size_t>(r)];
    DrapeFeatures f = drape_features(cloth::simulate_drape(params_for_record(p, rec), setup_for(r, seed, on_branch), ro, m_opt.model_options), rec);
    m_sim_seconds += std::chrono::duration<double>(Clock::now() - t0).count();
    ++m_simulations;
    return f;
}

void Evaluator::calibrate_spread(const Eigen::VectorXd& x, int extra)
{
    const cloth::FabricParams p = params_at(x);
    const int S = std::max(1, m_opt.seeds_per_evaluation);
    const int R = static_cast<int>(m_recs.size());
    std::vector<std::vector<double>> values; // [term][draw]
    m_cold.assign(static_cast<std::size_t>(R), {});
    m_cold_seeds.assign(static_cast<std::size_t>(R), 0);
    for (int r = 0; r < R; ++r) {
        const auto& meas = m_meas[static_cast<std::size_t>(r)];
        std::vector<DrapeFeatures> draws, cold;
        for (const auto& sim : m_best.sims[static_cast<std::size_t>(r)]) draws.push_back(drape_features(sim, m_recs[static_cast<std::size_t>(r)]));
        // The spread is measured on the fit's branch (the record and the fit's
        // drapes share its fold count); `cold_*` report the preset draped from
        // the random mix, as `drape predict` does - the same drapes when the fit
        // itself starts from the random mix.
        for (int k = 0; k < extra; ++k) draws.push_back(drape_cold(r, p, m_opt.seed + 1000 + static_cast<std::uint64_t>(k), true));
        if (branch_of(r) == 0)
            cold.assign(draws.end() - extra, draws.end());
        else
            for (int k = 0; k < m_opt.random_start_seeds; ++k)
                cold.push_back(drape_cold(r, p, m_opt.seed + 1000 + static_cast<std::uint64_t>(k), false));
        if (!cold.empty()) {
            std::vector<double> closed;
            m_cold[static_cast<std::size_t>(r)] = average_features(cold, &closed);
            m_cold_seeds[static_cast<std::size_t>(r)] = static_cast<int>(cold.size());
        }
        // Index of record r's first residual term.
        std::size_t base = 0;
        for (int q = 0; q < r; ++q) {
            const auto& mq = m_meas[static_cast<std::size_t>(q)];
            base += residual_terms(q, mq, mq, std::vector<double>(mq.contours.size(), 1.0), m_noise).size();
        }
        for (const auto& d : draws) {
            std::vector<double> closed;
            for (const auto& c : d.contours) closed.push_back(c.closed ? 1.0 : 0.0);
            const auto t = residual_terms(r, meas, d, closed, m_noise);
            if (values.size() < base + t.size()) values.resize(base + t.size());
            for (std::size_t i = 0; i < t.size(); ++i) values[base + i].push_back(t[i].simulated);
        }
    }
    const double both = std::sqrt(1.0 + 1.0 / S);
    m_sigma_floor.assign(values.size(), 0.0);
    const std::vector<ResidualTerm>& kinds = m_best.terms;
    for (std::size_t i = 0; i < values.size() && i < kinds.size(); ++i) {
        const auto& v = values[i];
        if (v.size() < 2 || kinds[i].kind == "closure") continue;
        double m = 0, ss = 0;
        for (double x0 : v) m += x0 / static_cast<double>(v.size());
        for (double x0 : v) ss += (x0 - m) * (x0 - m);
        const double sd = std::sqrt(ss / static_cast<double>(v.size() - 1));
        const auto r = static_cast<std::size_t>(kinds[i].record);
        const double corr = channel_of(kinds[i].kind) == "contours" ? std::sqrt(static_cast<double>(m_meas[r].contours.size())) : 1.0;
        m_sigma_floor[i] = both * corr * sd;
    }
    m_spread_calibrated = true;
    const Evaluation e = evaluate(x, Start::Best);
    m_best = e;
    m_best_x = x;
}

double Evaluator::objective(const Eigen::VectorXd& x, Start from, const std::string& stage)
{
    Evaluation e = evaluate(x, from);
    if (e.chi2 < m_best.chi2) {
        m_best = e;
        m_best_x = x;
        m_states.assign(e.sims.size(), {});
        for (std::size_t r = 0; r < e.sims.size(); ++r)
            for (const auto& s : e.sims[r]) m_states[r].push_back(s.x);
        m_have_states = true;
    }
    report(stage);
    return e.chi2;
}

void Evaluator::report(const std::string& stage) const
{
    if (!m_opt.progress) return;
    FitProgress p;
    p.stage = stage;
    p.evaluation = m_evaluations;
    p.planned = m_planned;
    p.best_chi2 = m_best.chi2;
    p.simulations = m_simulations;
    p.unconverged = m_unconverged;
    p.elapsed_s = std::chrono::duration<double>(Clock::now() - m_t0).count();
    p.last_coords.assign(m_last_x.data(), m_last_x.data() + m_last_x.size());
    m_opt.progress(p);
}

} // namespace drape::estimate::detail
