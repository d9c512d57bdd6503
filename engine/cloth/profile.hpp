#pragma once
// Where a solve's time goes: wall-time accumulators and call counts for the
// parts of a static (or implicit) iteration. Filled while ClothSystem::profile
// points at one; run_to_rest prints it under RestOptions::trace or when the
// environment variable DRAPE_PROFILE is set. Costs two clock reads per timed
// call (about 50 ns), nothing when no profile is attached.
#include <chrono>
#include <cstdio>
#include <string>

namespace drape::cloth {

struct SolveProfile {
    struct Part {
        double seconds = 0;
        long calls = 0;
    };
    Part forces;          ///< conservative_forces (includes the contact parts below)
    Part energy;          ///< potential_energy (includes the contact parts below)
    Part assemble;        ///< HessianAssembler::assemble (includes the contact parts below)
    Part vertex_contact;  ///< vertex-collider queries inside the three above
    Part edge_contact;    ///< edge-collider tests inside the three above
    Part self_contact;    ///< self-contact proximity searches and step bounds
    Part analyse;         ///< CHOLMOD symbolic analysis
    Part factorize;       ///< CHOLMOD numeric factorisation (calls include failed ones)
    Part solve;           ///< triangular solves
    Part line_search;     ///< line search: trial energies and residual checks (includes their forces/energy)
    long failed_factorizations = 0;
    long line_search_trials = 0;
    double total = 0;     ///< wall time of the solve [s]

    /// A markdown table of the parts, per iteration where `iterations` > 0.
    void print(std::FILE* out, const std::string& title, long iterations) const
    {
        std::fprintf(out, "%s: %.3f s, %ld iterations, %.2f ms per iteration\n", title.c_str(), total, iterations,
                     iterations > 0 ? 1e3 * total / double(iterations) : 0.0);
        std::fprintf(out, "| part | calls | total [s] | per call [ms] | per iteration [ms] | share |\n|---|---|---|---|---|---|\n");
        auto row = [&](const char* name, const Part& p) {
            std::fprintf(out, "| %s | %ld | %.3f | %.3f | %.3f | %.1f %% |\n", name, p.calls, p.seconds,
                         p.calls ? 1e3 * p.seconds / double(p.calls) : 0.0,
                         iterations > 0 ? 1e3 * p.seconds / double(iterations) : 0.0, total > 0 ? 100 * p.seconds / total : 0.0);
        };
        row("forces (all)", forces);
        row("energy (all)", energy);
        row("Hessian assembly", assemble);
        row("  of which vertex contact", vertex_contact);
        row("  of which edge contact", edge_contact);
        row("self-contact search and step bound", self_contact);
        row("CHOLMOD analyse", analyse);
        row("CHOLMOD factorise", factorize);
        row("CHOLMOD solve", solve);
        row("line search (energies, checks)", line_search);
        std::fprintf(out, "failed factorisations %ld, line-search trials %ld\n", failed_factorizations, line_search_trials);
    }
};

/// Adds the wall time of its scope to a profile part (no-op for nullptr).
class ProfileScope {
public:
    explicit ProfileScope(SolveProfile::Part* p) : m_p(p)
    {
        if (m_p) m_t0 = std::chrono::steady_clock::now();
    }
    ~ProfileScope()
    {
        if (m_p) {
            m_p->seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - m_t0).count();
            ++m_p->calls;
        }
    }
    ProfileScope(const ProfileScope&) = delete;
    ProfileScope& operator=(const ProfileScope&) = delete;

private:
    SolveProfile::Part* m_p;
    std::chrono::steady_clock::time_point m_t0;
};

} // namespace drape::cloth
