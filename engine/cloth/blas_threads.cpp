#include "engine/cloth/blas_threads.hpp"

#include <dlfcn.h>

namespace drape::cloth {

void single_threaded_blas()
{
    using SetThreads = void (*)(int);
    if (auto f = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"))) f(1);
}

} // namespace drape::cloth
