#include "engine/cloth/blas_threads.hpp"

#include <dlfcn.h>

#include <cstdlib>
#include <mutex>
#include <strings.h>

namespace drape::cloth {

namespace {

template <class F> F openblas(const char* name) { return reinterpret_cast<F>(dlsym(RTLD_DEFAULT, name)); }

} // namespace

std::string blas_kernel()
{
    auto corename = openblas<char* (*)()>("openblas_get_corename");
    const char* name = corename ? corename() : nullptr;
    return name ? std::string(name) : std::string("not OpenBLAS");
}

std::string portable_blas_kernel()
{
    static std::once_flag once;
    std::call_once(once, [] {
        if (std::getenv("OPENBLAS_CORETYPE")) return; // the user's choice, read at load
        if (const char* native = std::getenv("DRAPE_NATIVE_BLAS"); native && *native && std::string(native) != "0") return;
#if defined(__x86_64__)
        if (!__builtin_cpu_supports("avx2") || !__builtin_cpu_supports("fma")) return;
        auto corename = openblas<char* (*)()>("openblas_get_corename");
        auto quit = openblas<void (*)()>("gotoblas_dynamic_quit");
        auto init = openblas<void (*)()>("gotoblas_dynamic_init");
        if (!corename || !quit || !init) return; // not a dynamic-architecture OpenBLAS
        if (const char* now = corename(); now && strcasecmp(now, kPortableBlasKernel) == 0) return;
        // gotoblas_dynamic_init chooses the kernels again, by OPENBLAS_CORETYPE
        // when it is set (driver/others/dynamic.c); the variable is put back.
        setenv("OPENBLAS_CORETYPE", kPortableBlasKernel, 1);
        quit();
        init();
        unsetenv("OPENBLAS_CORETYPE");
        if (const char* now = corename(); !now || strcasecmp(now, kPortableBlasKernel) != 0) {
            // A build without those kernels (another list of cores): the machine's own again.
            quit();
            init();
        }
#endif
    });
    return blas_kernel();
}

void single_threaded_blas()
{
    portable_blas_kernel();
    using SetThreads = void (*)(int);
    if (auto f = openblas<SetThreads>("openblas_set_num_threads")) f(1);
}

} // namespace drape::cloth
