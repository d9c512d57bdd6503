#pragma once
// Shared by the libFuzzer targets (docs/reliability.md): a scratch folder per
// process (in /dev/shm when there is one, so the files cost no disk I/O), and
// invariants whose violation libFuzzer reports as a finding.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

/// The entry point of a target: libFuzzer's LLVMFuzzerTestOneInput in the fuzz
/// build, drape_fuzz_NAME when tests/fuzz compiles every target into one
/// executable to replay the regression inputs (DRAPE_FUZZ_REPLAY).
#ifdef DRAPE_FUZZ_REPLAY
#define DRAPE_FUZZ_TARGET(name) int drape_fuzz_##name
#else
#define DRAPE_FUZZ_TARGET(name) extern "C" int LLVMFuzzerTestOneInput
#endif

namespace drape::fuzz {

inline std::filesystem::path scratch_path()
{
    std::error_code ec;
    const std::filesystem::path base =
        std::filesystem::is_directory("/dev/shm", ec) ? std::filesystem::path("/dev/shm") : std::filesystem::temp_directory_path();
    return base / ("drape-fuzz-" + std::to_string(::getpid()));
}

/// This process's scratch folder, created on first use, removed at exit.
inline const std::filesystem::path& scratch()
{
    static const std::filesystem::path dir = [] {
        const auto d = scratch_path();
        std::filesystem::create_directories(d);
        std::atexit([] {
            std::error_code e;
            std::filesystem::remove_all(scratch_path(), e);
        });
        return d;
    }();
    return dir;
}

inline void write_file(const std::filesystem::path& p, const char* data, std::size_t size)
{
    std::ofstream f(p, std::ios::binary | std::ios::trunc);
    f.write(data, static_cast<std::streamsize>(size));
}

/// An invariant the code promises: a violation is a finding (abort with a message).
inline void require(bool ok, const char* what)
{
    if (!ok) {
        std::fprintf(stderr, "invariant violated: %s\n", what);
        std::abort();
    }
}

} // namespace drape::fuzz
