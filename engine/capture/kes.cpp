#include "engine/capture/kes.hpp"

#include <cmath>

namespace drape::capture {

double gider_drape_coefficient(const KesValues& k)
{
    // Gider (2004), as quoted in the seed paper, section 5.2.
    return 69.17 + 25.51 * k.two_hb - 35.69 * k.miu + 3.50 * k.g + 0.00049 * k.rt + 21.13 * k.wc - 0.492 * k.rc -
           13.04 * k.t0 + 0.303 * k.emc + 0.51 * k.w;
}

} // namespace drape::capture
