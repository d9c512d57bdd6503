#pragma once
// One small work-sharing loop for the core's independent jobs (the fit's
// perturbation seeds, a sensitivity study's drapes): n jobs on a few threads,
// each index taken once, the caller's thread working too.
#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace drape {

/// Calls fn(i) for every i in [0, n) on up to `threads` threads (the calling
/// thread is one of them). `stop()` is asked before each new index; once it
/// says true, no further index starts. The first exception fn throws is
/// rethrown here after every thread has finished (no index starts after it).
template <class Fn, class Stop>
void parallel_for(std::size_t n, int threads, Fn&& fn, Stop&& stop)
{
    std::atomic<std::size_t> next{0};
    std::exception_ptr error;
    std::mutex error_mutex;
    std::atomic<bool> failed{false};
    auto worker = [&] {
        for (;;) {
            if (failed.load() || stop()) return;
            const std::size_t i = next.fetch_add(1);
            if (i >= n) return;
            try {
                fn(i);
            } catch (...) {
                std::lock_guard lock(error_mutex);
                if (!error) error = std::current_exception();
                failed = true;
                return;
            }
        }
    };
    const int nthreads = std::clamp(threads, 1, static_cast<int>(std::max<std::size_t>(n, 1)));
    std::vector<std::thread> pool;
    for (int t = 1; t < nthreads; ++t) pool.emplace_back(worker);
    worker();
    for (auto& t : pool) t.join();
    if (error) std::rethrow_exception(error);
}

template <class Fn>
void parallel_for(std::size_t n, int threads, Fn&& fn)
{
    parallel_for(n, threads, std::forward<Fn>(fn), [] { return false; });
}

} // namespace drape
