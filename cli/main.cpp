// The headless `drape` command: dispatches to the registered sub-commands.
#include "cli/command.hpp"

#include "engine/cloth/blas_threads.hpp"
#include "engine/core/error.hpp"
#include "engine/core/text.hpp"

#include <cstdio>
#include <cstdlib>
#include <new>
#include <exception>
#include <iostream>

#if defined(__GLIBC__)
#include <malloc.h> // mallopt
#endif

// Defense in depth for the readers Drapekit does not control (assimp, through
// `drape import` and the garment commands): one allocation of more than
// kMaxAllocation is refused with std::bad_alloc, which assimp reports as a
// failed import. A corrupt Collada file made assimp allocate 1.5 GiB, then
// 3 GiB (12 GB resident) before failing; the cap ends that at the first.
// Nothing of Drapekit's own allocates that much at once through new (a
// 20-million-vertex mesh is 480 MB; Eigen, OpenCV and CHOLMOD use malloc).
namespace {
constexpr std::size_t kMaxAllocation = std::size_t(1) << 30;
void* checked_alloc(std::size_t n)
{
    if (n > kMaxAllocation) throw std::bad_alloc();
    if (void* p = std::malloc(n ? n : 1)) return p;
    throw std::bad_alloc();
}
} // namespace
void* operator new(std::size_t n) { return checked_alloc(n); }
void* operator new[](std::size_t n) { return checked_alloc(n); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
// The nothrow forms too (std::stable_sort's temporary buffer uses them): every
// new that the deletes above free must come from malloc, or a sanitizer build
// reports an alloc-dealloc mismatch against its own nothrow new.
void* operator new(std::size_t n, const std::nothrow_t&) noexcept { return n > kMaxAllocation ? nullptr : std::malloc(n ? n : 1); }
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept { return n > kMaxAllocation ? nullptr : std::malloc(n ? n : 1); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }

namespace {
/// A message for the terminal: messages quote names, cells and paths from
/// files a user may have received, so control characters (escape sequences)
/// and bytes that are not UTF-8 are written as \xNN; line breaks are kept.
std::string safe(const std::string& message)
{
    std::string out;
    std::size_t start = 0;
    while (true) {
        const std::size_t nl = message.find('\n', start);
        out += drape::printable(std::string_view(message).substr(start, nl == std::string::npos ? std::string::npos : nl - start), 4000);
        if (nl == std::string::npos) break;
        out += '\n';
        start = nl + 1;
    }
    return out;
}

void print_overview()
{
    std::cout << "usage: drape COMMAND [ARGS]\n\ncommands:\n";
    for (const auto& [name, c] : drape::cli::registry())
        std::printf("  %-12s %s\n", name.c_str(), c.summary.c_str());
    std::cout << "\n`drape help COMMAND` shows a command's flags.\n";
}
} // namespace

int main(int argc, char** argv)
{
    using namespace drape::cli;
#if defined(__GLIBC__)
    // Keep freed memory in the process. A photo measurement allocates and frees
    // image buffers of several MB dozens of times; glibc maps each one afresh
    // (mmap above its threshold, and trims the heap's top) and the next one
    // faults in again page by page: on a virtual machine that was 44 % of
    // `drape measure` (three test scenes 12.4 -> 7.0 s; a drape 8 %). The
    // process keeps at most its own peak; a library host decides for itself.
    // (A glibc before 2.35 caps the threshold at 32 MB and refuses this; then the
    // trim threshold is left alone too, which would switch off glibc's own
    // raising of the threshold.)
    if (mallopt(M_MMAP_THRESHOLD, 256 << 20) == 1) mallopt(M_TRIM_THRESHOLD, 512 << 20);
#endif
    drape::cloth::portable_blas_kernel(); // before any thread (it sets the environment)
    std::vector<std::string> args(argv + 1, argv + argc);
    if (args.empty() || args[0] == "--help" || args[0] == "-h") {
        print_overview();
        return args.empty() ? 2 : 0;
    }
    if (args[0] == "help") {
        if (args.size() > 1) {
            auto it = registry().find(args[1]);
            if (it == registry().end()) {
                std::cerr << "drape: unknown command '" << args[1] << "'\n";
                return 2;
            }
            std::cout << it->second.usage << "\n";
            return 0;
        }
        print_overview();
        return 0;
    }
    auto it = registry().find(args[0]);
    if (it == registry().end()) {
        std::cerr << "drape: unknown command '" << args[0] << "' (see `drape --help`)\n";
        return 2;
    }
    std::vector<std::string> rest(args.begin() + 1, args.end());
    for (const auto& a : rest)
        if (a == "--help" || a == "-h") {
            std::cout << it->second.usage << "\n";
            return 0;
        }
    try {
        return it->second.run(rest);
    } catch (const UsageError& e) {
        std::cerr << "drape " << args[0] << ": " << safe(e.what()) << "\n\n" << it->second.usage << "\n";
        return 2;
    } catch (const drape::Error& e) {
        std::cerr << "drape " << args[0] << ": error: " << safe(e.what()) << "\n";
        return 1;
    } catch (const std::bad_alloc&) {
        std::cerr << "drape " << args[0] << ": out of memory (or one allocation above " << (kMaxAllocation >> 20)
                  << " MiB was refused)\n";
        return 3;
    } catch (const std::exception& e) {
        std::cerr << "drape " << args[0] << ": internal error: " << safe(e.what()) << "\n";
        return 3;
    }
}
