#pragma once
// A drape coefficient from Kawabata (KES-FB) values: the regression the seed
// paper quotes. Unrelated to photos; kept beside the measurements it is compared with.

namespace drape::capture {

/// Gider (2004) KES regression quoted in the seed paper (section 5.2). Inputs in
/// the KES-FB units: two_hb [gf cm/cm], miu [-], g [gf/(cm deg)], rt [%],
/// wc [gf cm/cm^2], rc [%], t0 [mm], emc [%], w [mg/cm^2]. Returns DC [%].
struct KesValues {
    double two_hb = 0, miu = 0, g = 0, rt = 0, wc = 0, rc = 0, t0 = 0, emc = 0, w = 0;
};
double gider_drape_coefficient(const KesValues& k);

} // namespace drape::capture
