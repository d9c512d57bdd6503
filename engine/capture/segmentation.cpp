#include "engine/capture/segmentation.hpp"

#include "engine/capture/pixels.hpp"
#include "engine/capture/scale.hpp"
#include "engine/core/error.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace drape::capture {

using namespace detail;

FabricModel fabric_model(const record::Record& rec, const record::Camera& cam, const cv::Mat& lab)
{
    FabricModel m;
    std::vector<double> L, A, B;
    // Fabric: the pedestal top is always covered by the specimen.
    for (double r = 0; r <= 0.6 * rec.R2; r += 0.003)
        for (int k = 0; k < 90; ++k) {
            const double th = 2 * M_PI * k / 90;
            const cv::Vec3f v = sample(lab, cam.project({r * std::cos(th), r * std::sin(th), 0.0}));
            L.push_back(v[0]);
            A.push_back(v[1]);
            B.push_back(v[2]);
        }
    m.fabric_lab = {median(L), median(A), median(B)};
    double var = 0;
    for (double l : L) var += (l - m.fabric_lab[0]) * (l - m.fabric_lab[0]);
    m.fabric_L_sd = std::sqrt(var / static_cast<double>(L.size()));
    // Floor: a ring beyond the specimen's reach and inside the chessboards.
    L.clear();
    A.clear();
    B.clear();
    const double reach = rec.specimen.max_reach();
    for (double r = reach + 0.035; r <= reach + 0.06; r += 0.005)
        for (int k = 0; k < 180; ++k) {
            const double th = 2 * M_PI * k / 180;
            const Eigen::Vector2d px = cam.project({r * std::cos(th), r * std::sin(th), -rec.pedestal_height});
            if (!(px.x() >= 0 && px.y() >= 0 && px.x() < lab.cols && px.y() < lab.rows)) continue;
            const cv::Vec3f v = sample(lab, px);
            L.push_back(v[0]);
            A.push_back(v[1]);
            B.push_back(v[2]);
        }
    m.floor_lab = {median(L), median(A), median(B)};
    const double chroma = std::hypot(m.fabric_lab[1] - m.floor_lab[1], m.fabric_lab[2] - m.floor_lab[2]);
    // Shadows on the white floor are grey: they change L* but hardly a*, b*.
    // A coloured fabric is therefore segmented by chroma alone, which ignores
    // its own shading and the floor's shadows; a grey fabric by darkness.
    m.chromatic = chroma >= 12.0;
    m.contrast = m.chromatic ? chroma : std::abs(m.floor_lab[0] - m.fabric_lab[0]);
    return m;
}

cv::Mat fabric_probability(const cv::Mat& lab, const FabricModel& m)
{
    cv::Mat p(lab.size(), CV_32F);
    const double da = m.fabric_lab[1] - m.floor_lab[1], db = m.fabric_lab[2] - m.floor_lab[2];
    const double n2 = da * da + db * db;
    // Grey fabric: p = 0.5 at max(6, 3 sd) L* units above the fabric's own level,
    // i.e. as close to the fabric as its noise allows, because the contact
    // shadow around the hem is dark too.
    const double half = std::max(6.0, 3.0 * m.fabric_L_sd);
    const bool darker = m.fabric_lab[0] < m.floor_lab[0];
    for (int y = 0; y < lab.rows; ++y) {
        const cv::Vec3f* in = lab.ptr<cv::Vec3f>(y);
        float* out = p.ptr<float>(y);
        for (int x = 0; x < lab.cols; ++x) {
            double v;
            if (m.chromatic)
                v = ((in[x][1] - m.floor_lab[1]) * da + (in[x][2] - m.floor_lab[2]) * db) / n2;
            else if (darker)
                v = 1.0 - (in[x][0] - m.fabric_lab[0]) / (2 * half);
            else
                v = 1.0 - (m.fabric_lab[0] - in[x][0]) / (2 * half);
            out[x] = static_cast<float>(std::clamp(v, 0.0, 1.0));
        }
    }
    return p;
}

cv::Mat detail::central_component(const cv::Mat& prob, const Eigen::Vector2d& centre, double max_radius_px)
{
    cv::Mat bin = prob >= 0.5;
    cv::Mat limit = cv::Mat::zeros(prob.size(), CV_8U);
    cv::circle(limit, cv::Point(static_cast<int>(centre.x()), static_cast<int>(centre.y())),
               static_cast<int>(max_radius_px), 255, cv::FILLED);
    bin &= limit;
    cv::morphologyEx(bin, bin, cv::MORPH_OPEN, cv::getStructuringElement(cv::MORPH_ELLIPSE, {3, 3}));
    cv::Mat labels;
    cv::connectedComponents(bin, labels, 8, CV_32S);
    const int cxp = std::clamp(static_cast<int>(centre.x()), 0, prob.cols - 1);
    const int cyp = std::clamp(static_cast<int>(centre.y()), 0, prob.rows - 1);
    const int id = labels.at<int>(cyp, cxp);
    cv::Mat gate = cv::Mat::zeros(prob.size(), CV_8U);
    if (id == 0) return gate;
    gate = labels == id;
    cv::dilate(gate, gate, cv::getStructuringElement(cv::MORPH_ELLIPSE, {5, 5}));
    return gate;
}

// ---- single photos ------------------------------------------------------------

namespace {

/// Polygon of world points at z = 0 along 720 rays: radius f(theta) [m], in
/// image pixels times `scale`.
template <class F>
std::vector<cv::Point> ring_px(const record::Camera& cam, F radius, double scale)
{
    std::vector<cv::Point> pts;
    for (int k = 0; k < 720; ++k) {
        const double th = 2 * M_PI * k / 720;
        const double r = radius(th);
        const Eigen::Vector2d u = cam.project({r * std::cos(th), r * std::sin(th), 0.0});
        if (!std::isfinite(u.x())) continue;
        pts.emplace_back(static_cast<int>(std::lround(u.x() * scale)), static_cast<int>(std::lround(u.y() * scale)));
    }
    return pts;
}

cv::Mat fill(const cv::Size& size, const std::vector<cv::Point>& poly)
{
    cv::Mat m = cv::Mat::zeros(size, CV_8U);
    if (poly.size() >= 3) cv::fillPoly(m, std::vector<std::vector<cv::Point>>{poly}, cv::Scalar(255));
    return m;
}

/// Colour clusters (k-means) of the masked pixels of a 3-channel float image;
/// centres and their shares.
struct Clusters {
    std::vector<cv::Vec3f> centre;
    std::vector<double> share;
};

Clusters clusters(const cv::Mat& img, const cv::Mat& mask, int k)
{
    std::vector<cv::Vec3f> px;
    const int total = cv::countNonZero(mask);
    const int stride = std::max(1, total / 20000);
    int i = 0;
    for (int y = 0; y < img.rows; ++y)
        for (int x = 0; x < img.cols; ++x)
            if (mask.at<uchar>(y, x) && (i++ % stride) == 0) px.push_back(img.at<cv::Vec3f>(y, x));
    Clusters c;
    if (px.size() < static_cast<std::size_t>(k) * 4) return c;
    cv::Mat data(static_cast<int>(px.size()), 3, CV_32F, px.data());
    cv::Mat labels, centres;
    cv::setRNGSeed(7);
    cv::kmeans(data, k, labels, cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 30, 0.1), 2,
               cv::KMEANS_PP_CENTERS, centres);
    std::vector<int> count(static_cast<std::size_t>(k), 0);
    for (int r = 0; r < labels.rows; ++r) ++count[static_cast<std::size_t>(labels.at<int>(r))];
    for (int j = 0; j < k; ++j) {
        c.centre.emplace_back(centres.at<float>(j, 0), centres.at<float>(j, 1), centres.at<float>(j, 2));
        c.share.push_back(static_cast<double>(count[static_cast<std::size_t>(j)]) / static_cast<double>(labels.rows));
    }
    return c;
}

double wdist(const cv::Vec3f& a, const cv::Vec3f& b, double wL)
{
    return std::sqrt(wL * wL * (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

cv::Vec3f masked_median(const cv::Mat& lab, const cv::Mat& mask)
{
    std::vector<double> c[3];
    const int total = cv::countNonZero(mask);
    const int stride = std::max(1, total / 20000);
    int i = 0;
    for (int y = 0; y < lab.rows; ++y)
        for (int x = 0; x < lab.cols; ++x)
            if (mask.at<uchar>(y, x) && (i++ % stride) == 0)
                for (int j = 0; j < 3; ++j) c[j].push_back(lab.at<cv::Vec3f>(y, x)[j]);
    return {static_cast<float>(median(c[0])), static_cast<float>(median(c[1])), static_cast<float>(median(c[2]))};
}

/// The component of `bin` that overlaps `seed` most (all of them when `seed` is empty).
cv::Mat component_through(const cv::Mat& bin, const cv::Mat& seed)
{
    cv::Mat labels;
    const int n = cv::connectedComponents(bin, labels, 8, CV_32S);
    std::vector<int> hits(static_cast<std::size_t>(n), 0);
    for (int y = 0; y < bin.rows; ++y)
        for (int x = 0; x < bin.cols; ++x)
            if (seed.at<uchar>(y, x)) ++hits[static_cast<std::size_t>(labels.at<int>(y, x))];
    int best = 0, best_hits = 0;
    for (int i = 1; i < n; ++i)
        if (hits[static_cast<std::size_t>(i)] > best_hits) {
            best = i;
            best_hits = hits[static_cast<std::size_t>(i)];
        }
    cv::Mat out = cv::Mat::zeros(bin.size(), CV_8U);
    if (best > 0 && hits[static_cast<std::size_t>(best)] > 0) out = labels == best;
    return out;
}

/// Sub-pixel edge: in a band around the region's boundary, the fraction of
/// cloth colour in each pixel between the mean cloth colour just inside and
/// the mean background colour just outside (channel weights w). A blurred
/// step is symmetric, so the 0.5 crossing is where the step is.
cv::Mat refine_edge(const cv::Mat& lab, const cv::Mat& region, double wL)
{
    cv::Mat M;
    region.convertTo(M, CV_32F, 1.0 / 255);
    // Cores 2 px inside and outside the boundary, means over 13 x 13 px, a
    // band of 3 px either side. (Tried 3/5/8 px cores, 17 and 21 px windows:
    // within 0.4 points of each other on the synthetic scenes.)
    const auto k5 = cv::getStructuringElement(cv::MORPH_ELLIPSE, {5, 5});
    const auto k7 = cv::getStructuringElement(cv::MORPH_ELLIPSE, {7, 7});
    cv::Mat fcore, bcore, inv = 255 - region;
    cv::erode(region, fcore, k5);
    cv::erode(inv, bcore, k5);
    cv::Mat band = cv::Mat::zeros(region.size(), CV_8U), d1, d2;
    cv::dilate(region, d1, k7);
    cv::dilate(inv, d2, k7);
    band = d1 & d2;
    cv::Mat F, B;
    fcore.convertTo(F, CV_32F, 1.0 / 255);
    bcore.convertTo(B, CV_32F, 1.0 / 255);
    const cv::Size win(13, 13);
    cv::Mat nF, nB;
    cv::boxFilter(F, nF, CV_32F, win, {-1, -1}, false);
    cv::boxFilter(B, nB, CV_32F, win, {-1, -1}, false);
    std::vector<cv::Mat> ch;
    cv::split(lab, ch);
    std::vector<cv::Mat> mF(3), mB(3);
    for (int c = 0; c < 3; ++c) {
        cv::boxFilter(ch[static_cast<std::size_t>(c)].mul(F), mF[static_cast<std::size_t>(c)], CV_32F, win, {-1, -1}, false);
        cv::boxFilter(ch[static_cast<std::size_t>(c)].mul(B), mB[static_cast<std::size_t>(c)], CV_32F, win, {-1, -1}, false);
    }
    cv::Mat p = M.clone();
    const double w[3] = {wL * wL, 1.0, 1.0};
    for (int y = 0; y < lab.rows; ++y) {
        const uchar* bd = band.ptr<uchar>(y);
        float* out = p.ptr<float>(y);
        const cv::Vec3f* in = lab.ptr<cv::Vec3f>(y);
        for (int x = 0; x < lab.cols; ++x) {
            if (!bd[x]) continue;
            const float cf = nF.at<float>(y, x), cb = nB.at<float>(y, x);
            if (cf < 3 || cb < 3) continue;
            double num = 0, den = 0;
            for (int c = 0; c < 3; ++c) {
                const double f = mF[static_cast<std::size_t>(c)].at<float>(y, x) / cf;
                const double b = mB[static_cast<std::size_t>(c)].at<float>(y, x) / cb;
                num += w[c] * (in[x][c] - b) * (f - b);
                den += w[c] * (f - b) * (f - b);
            }
            if (den < 9.0) continue; // too little local contrast: keep the region's own edge
            out[x] = static_cast<float>(std::clamp(num / den, 0.0, 1.0));
        }
    }
    return p;
}

struct Threshold {
    int channel = 0;
    bool below = true;
    double value = 0;
};

Threshold parse_threshold(const std::string& t)
{
    Threshold th;
    const std::string bad = "threshold '" + t + "': expected CHANNEL<VALUE or CHANNEL>VALUE with CHANNEL one of L, a, b "
                            "(CIE L*a*b*: L 0..100, a and b about -100..100), e.g. L<60";
    if (t.size() < 3) throw ParameterError(bad);
    const char c = t[0];
    if (c == 'L' || c == 'l') th.channel = 0;
    else if (c == 'a') th.channel = 1;
    else if (c == 'b') th.channel = 2;
    else throw ParameterError(bad);
    if (t[1] != '<' && t[1] != '>') throw ParameterError(bad);
    th.below = t[1] == '<';
    char* end = nullptr;
    th.value = std::strtod(t.c_str() + 2, &end);
    if (!end || *end != '\0' || !std::isfinite(th.value)) throw ParameterError(bad);
    return th;
}

} // namespace

std::vector<cv::Point> search_limit_px(const record::Record& rec, const record::Camera& cam, double specimen_angle, double scale,
                                       double factor)
{
    record::Specimen sp = rec.specimen;
    const bool known = std::isfinite(specimen_angle);
    if (known) sp.angle = specimen_angle;
    const double rmax = sp.max_reach();
    return ring_px(cam, [&](double th) {
        // 3 mm beyond where the tracer starts (top_view.cpp: the same margin),
        // so that a region running into the limit is seen there.
        const double r = known ? sp.reach(th) : rmax;
        return factor * (r + std::max(0.02, 0.05 * r)) + 0.003;
    }, scale);
}

namespace {

/// The cloth by a threshold on one L*a*b* channel (--threshold), ramped over 2 x 4
/// units for a smooth edge.
PhotoSegmentation threshold_segmentation(const cv::Mat& lab, const SegmentOverrides& ov, const cv::Mat& disc_full, PhotoSegmentation seg)
{
    const cv::Size full = lab.size();
    const Threshold th = parse_threshold(ov.threshold);
    cv::Mat chan;
    cv::extractChannel(lab, chan, th.channel);
    constexpr double ramp = 4.0; // p runs 0..1 over 2 x 4 units around the threshold
    cv::Mat p(full, CV_32F);
    for (int y = 0; y < full.height; ++y)
        for (int x = 0; x < full.width; ++x) {
            const double v = chan.at<float>(y, x);
            p.at<float>(y, x) = static_cast<float>(std::clamp(0.5 + (th.below ? th.value - v : v - th.value) / (2 * ramp), 0.0, 1.0));
        }
    p.setTo(1.0f, disc_full);
    cv::Mat bin = (p >= 0.5f) & seg.limit;
    bin |= disc_full;
    cv::morphologyEx(bin, bin, cv::MORPH_OPEN, cv::getStructuringElement(cv::MORPH_ELLIPSE, {3, 3}));
    seg.region = component_through(bin, disc_full);
    seg.prob = p;
    cv::dilate(seg.region, seg.gate, cv::getStructuringElement(cv::MORPH_ELLIPSE, {5, 5}));
    seg.method = "threshold " + ov.threshold + " (manual)";
    return seg;
}

/// The photo at GrabCut's working size (it is O(pixels) per iteration, several
/// iterations; the edge is refined at full size afterwards) and the regions there
/// that seed and check it.
struct Working {
    double ws = 1;
    cv::Mat sbgr, slab;
    cv::Size ss;
    cv::Mat limit, disc, disc_all, disc_paint, ring, frame;
    cv::Mat bg_seed, bg_train, beyond_band;
    cv::Mat user_fg, user_bg;
};

Working working_regions(const cv::Mat& bgr, const cv::Mat& lab, const record::Record& rec, const record::Camera& cam, double specimen_angle)
{
    Working w;
    const cv::Size full = bgr.size();
    w.ws = std::min(1.0, 1000.0 / std::max(full.width, full.height));
    cv::resize(bgr, w.sbgr, {}, w.ws, w.ws, cv::INTER_AREA);
    cv::resize(lab, w.slab, w.sbgr.size(), 0, 0, cv::INTER_AREA);
    const cv::Size ss = w.ss = w.sbgr.size();
    const double ws = w.ws;
    w.limit = fill(ss, search_limit_px(rec, cam, specimen_angle, ws));
    w.disc = fill(ss, ring_px(cam, [&](double) { return 0.95 * rec.R2; }, ws));
    // The whole disc is inside the drape's vertical projection; an upper
    // disc's edge is painted over a little beyond it.
    w.disc_all = fill(ss, ring_px(cam, [&](double) { return 0.99 * rec.R2; }, ws));
    w.disc_paint = fill(ss, ring_px(cam, [&](double) { return 1.025 * rec.R2; }, ws));
    w.ring = fill(ss, ring_px(cam, [&](double) { return 1.12 * rec.R2; }, ws)) & ~fill(ss, ring_px(cam, [&](double) { return 1.03 * rec.R2; }, ws));
    const int band = std::max(2, std::min(ss.width, ss.height) / 60);
    w.frame = cv::Mat::zeros(ss, CV_8U);
    cv::rectangle(w.frame, cv::Rect(0, 0, ss.width, ss.height), cv::Scalar(255), 2 * band);
    // Hard background: beyond the search limit. The photo's frame inside the
    // limit only teaches the background's colours (a drape running off the
    // photo must be seen to touch its border). The background's colours come
    // from further out than 1.15 x the limit, so that a band just outside it
    // can be checked: cloth colours there mean the drape does not end where a
    // specimen of this size must.
    w.bg_seed = ~w.limit;
    const cv::Mat far_inside = fill(ss, search_limit_px(rec, cam, specimen_angle, ws, 1.15));
    w.bg_train = ~far_inside | w.frame;
    if (cv::countNonZero(w.bg_train) < ss.area() / 50) w.bg_train = w.bg_seed | w.frame;
    w.beyond_band = far_inside & ~w.limit;
    return w;
}

/// The user's mask (--mask): a complete one (white and black only) is the region
/// itself, returned; a partial one seeds GrabCut (w.user_fg, w.user_bg).
std::optional<cv::Mat> user_mask(const SegmentOverrides& ov, const cv::Size& full, const cv::Mat& disc_full, Working& w)
{
    if (ov.mask.empty()) return std::nullopt;
    if (ov.mask.size() != full)
        throw FileError(ov.mask_name + ": the mask is " + std::to_string(ov.mask.cols) + " x " + std::to_string(ov.mask.rows) + " px, the photo " +
                        std::to_string(full.width) + " x " + std::to_string(full.height) + " px");
    cv::Mat grey = ov.mask;
    if (grey.channels() == 3) cv::cvtColor(grey, grey, cv::COLOR_BGR2GRAY);
    const cv::Mat white = grey >= 200, black = grey <= 55;
    if (cv::countNonZero(white) + cv::countNonZero(black) == full.area()) {
        // A complete mask: what the user drew is what is counted.
        const cv::Mat region = component_through(white, disc_full);
        if (cv::countNonZero(region & disc_full) < cv::countNonZero(disc_full) / 2)
            throw RefusalError({"mask-misses-disc", ov.mask_name + ": the mask's white part does not cover the disc",
                                "the mask must be white on the cloth (disc included), black elsewhere, same size as the photo"});
        return region;
    }
    cv::resize(white, w.user_fg, w.ss, 0, 0, cv::INTER_NEAREST);
    cv::resize(black, w.user_bg, w.ss, 0, 0, cv::INTER_NEAREST);
    w.bg_seed |= w.user_bg;
    return std::nullopt;
}

/// The cloth's and the background's colours, and how much L* counts against them.
struct ColourModel {
    Clusters fg, bg;
    cv::Vec3f ring_median;
    cv::Mat fg_sample;
    double wL = 1;
};

/// Colour samples: the cloth on the disc and just outside its rim, the background
/// beyond the specimen's reach. Refuses when either is missing or they cannot be
/// told apart.
ColourModel colour_model(const Working& w, PhotoSegmentation& seg)
{
    ColourModel cm;
    cm.bg = clusters(w.slab, w.bg_train, 5);
    if (cm.bg.centre.empty())
        throw RefusalError({"no-background", "too little background around the drape to learn its colour",
                            "photograph the drape with a margin of background all round, or give --mask"});
    // An upper disc (a clamp) on the cloth has its own colour: when the disc's
    // top differs from the cloth just outside its rim and looks like the
    // background, it must not teach the cloth's colours (it is counted anyway).
    const cv::Vec3f disc_med = masked_median(w.slab, w.disc);
    cm.ring_median = masked_median(w.slab, w.ring);
    double disc_to_bg = 1e9;
    for (const auto& c : cm.bg.centre) disc_to_bg = std::min(disc_to_bg, wdist(disc_med, c, 1.0));
    seg.clamp_disc = wdist(disc_med, cm.ring_median, 1.0) > 15.0 && disc_to_bg < 12.0;
    cm.fg_sample = seg.clamp_disc ? w.ring.clone() : (w.disc | w.ring);
    if (!w.user_fg.empty()) cm.fg_sample |= w.user_fg;
    cm.fg = clusters(w.slab, cm.fg_sample & ~w.bg_seed, 3);
    if (cm.fg.centre.empty())
        throw RefusalError({"no-cloth-sample", "the disc and its rim are not in the photo's search region",
                            "check the disc position (--disc-px) and the scale"});
    // Cloth and background differ in colour (a*, b*)? Then L* counts less:
    // shadows and the cloth's own shading change L* and hardly the chroma.
    // The cloth's typical colour (its median on the disc and the rim ring)
    // against the nearest background colour.
    const cv::Vec3f fg_med = masked_median(w.slab, cm.fg_sample & ~w.bg_seed);
    double ab_sep = 1e9, lab_sep = 1e9;
    for (std::size_t j = 0; j < cm.bg.centre.size(); ++j) {
        if (cm.bg.share[j] < 0.05) continue;
        ab_sep = std::min(ab_sep, wdist(fg_med, cm.bg.centre[j], 0.0));
        lab_sep = std::min(lab_sep, wdist(fg_med, cm.bg.centre[j], 1.0));
    }
    cm.wL = ab_sep >= 10.0 ? 0.3 : 1.0;
    seg.contrast = cm.wL < 1 ? ab_sep : lab_sep;
    if (seg.contrast < 4.0)
        throw RefusalError({"low-contrast",
                            "the cloth cannot be told from the background: its typical colour is " + fmt("%.1f", seg.contrast) +
                                " L*a*b* units from a colour found beyond the specimen's reach (a background like the cloth, "
                                "or a shadow as dark as the cloth)",
                            "give a threshold (--threshold L<NN or L>NN, a.., b..) or a mask image (--mask FILE.png, white = "
                            "cloth), or photograph on a contrasting background without the rig's shadow"});
    return cm;
}

/// Whether pixel colour v is nearer the cloth's colours than the background's.
bool cloth_coloured(const cv::Vec3f& v, const ColourModel& cm)
{
    double dfg = 1e9, dbg = 1e9;
    for (const auto& c : cm.fg.centre) dfg = std::min(dfg, wdist(v, c, cm.wL));
    for (const auto& c : cm.bg.centre) dbg = std::min(dbg, wdist(v, c, cm.wL));
    return dfg < dbg;
}

/// Refuses when the band just outside the search limit has the cloth's colours.
void check_beyond_limit(const record::Record& rec, const Working& w, const ColourModel& cm, PhotoSegmentation& seg)
{
    int cloth_like = 0, total = 0;
    for (int y = 0; y < w.ss.height; ++y)
        for (int x = 0; x < w.ss.width; ++x) {
            if (!w.beyond_band.at<uchar>(y, x)) continue;
            ++total;
            if (cloth_coloured(w.slab.at<cv::Vec3f>(y, x), cm)) ++cloth_like;
        }
    seg.beyond_limit_fraction = total > 0 ? static_cast<double>(cloth_like) / total : 0.0;
    if (seg.beyond_limit_fraction > 0.15) {
        seg.limit_band = w.beyond_band;
        throw RefusalError({"search-limit",
                            fmt("%.0f", 100 * seg.beyond_limit_fraction) +
                                " % of a band just outside the search limit (the flat specimen's edge + 5 %) has the cloth's "
                                "colours: the drape, or something like it, continues beyond where a " +
                                rec.specimen.describe() + " specimen can hang",
                            "check --specimen and --disc (diameters) and the scale (a ruler's px/mm, the markers' size); "
                            "the overlay shows the limit as a yellow line. Otherwise give --threshold or --mask"});
    }
}

/// GrabCut on (wL L*, a*, b*) as 8-bit at the working size, seeded by the disc,
/// the search limit and the colour model; the cloth's outer outline, back at full
/// size.
cv::Mat grabcut_region(const Working& w, const ColourModel& cm, bool clamp_disc, const cv::Size& full)
{
    const cv::Size ss = w.ss;
    // An upper disc is painted over with the cloth's colours (pixels of the rim
    // ring, drawn at random), so that it neither teaches the cloth model its own
    // colour nor makes a degenerate colour cluster.
    std::vector<cv::Vec3f> ring_px_colours;
    if (clamp_disc)
        for (int y = 0; y < ss.height; ++y)
            for (int x = 0; x < ss.width; ++x)
                if (w.ring.at<uchar>(y, x)) ring_px_colours.push_back(w.slab.at<cv::Vec3f>(y, x));
    cv::RNG paint(99);
    cv::Mat gimg(ss, CV_8UC3);
    for (int y = 0; y < ss.height; ++y)
        for (int x = 0; x < ss.width; ++x) {
            cv::Vec3f v = w.slab.at<cv::Vec3f>(y, x);
            if (clamp_disc && w.disc_paint.at<uchar>(y, x))
                v = ring_px_colours.empty() ? cm.ring_median
                                            : ring_px_colours[static_cast<std::size_t>(paint.uniform(0, static_cast<int>(ring_px_colours.size())))];
            gimg.at<cv::Vec3b>(y, x) = cv::Vec3b(cv::saturate_cast<uchar>(v[0] * 2.55 * cm.wL), cv::saturate_cast<uchar>(v[1] + 128),
                                                 cv::saturate_cast<uchar>(v[2] + 128));
        }
    cv::Mat mask(ss, CV_8U);
    for (int y = 0; y < ss.height; ++y)
        for (int x = 0; x < ss.width; ++x)
            mask.at<uchar>(y, x) = cloth_coloured(w.slab.at<cv::Vec3f>(y, x), cm) && !w.frame.at<uchar>(y, x) ? cv::GC_PR_FGD : cv::GC_PR_BGD;
    mask.setTo(cv::GC_BGD, w.bg_seed);
    mask.setTo(cv::GC_FGD, w.disc_all);
    if (!w.user_fg.empty()) mask.setTo(cv::GC_FGD, w.user_fg & ~w.user_bg);
    cv::Mat bgd, fgd;
    // GrabCut's own k-means draws from OpenCV's global generator: seeded, so
    // that a photo gives the same answer every time.
    // (Seeds 1, 2, 3 and this one agree within 0.3 points on every scene of
    // tst_photo but the print with a background-coloured element: 47.6..49.0.)
    cv::setRNGSeed(12345);
    cv::grabCut(gimg, mask, cv::Rect(), bgd, fgd, 5, cv::GC_INIT_WITH_MASK);
    cv::Mat bin = (mask == cv::GC_FGD) | (mask == cv::GC_PR_FGD);
    cv::morphologyEx(bin, bin, cv::MORPH_OPEN, cv::getStructuringElement(cv::MORPH_ELLIPSE, {3, 3}));
    bin |= w.disc_all;
    bin = component_through(bin, w.disc);
    // Holes inside the cloth (a sparkle, a print's background-coloured spot)
    // are cloth: only the outline counts.
    bin = fill_holes(bin);
    if (w.ws >= 1.0) return bin;
    cv::Mat f;
    bin.convertTo(f, CV_32F, 1.0 / 255);
    cv::resize(f, f, full, 0, 0, cv::INTER_LINEAR);
    return f >= 0.5f;
}

/// The segmentation's result from a region: its edge refined at full size (or the
/// region as it is) and the gate around it.
PhotoSegmentation finished(PhotoSegmentation seg, const cv::Mat& lab, const cv::Mat& region, double wL, bool refine)
{
    seg.region = region;
    if (refine) seg.prob = refine_edge(lab, region, wL);
    else region.convertTo(seg.prob, CV_32F, 1.0 / 255);
    cv::dilate(region, seg.gate, cv::getStructuringElement(cv::MORPH_ELLIPSE, {9, 9}));
    seg.lightness_weight = wL;
    return seg;
}

} // namespace

PhotoSegmentation segment_photo(const cv::Mat& bgr, const cv::Mat& lab, const record::Record& rec, const record::Camera& cam,
                                const SegmentOverrides& ov, double specimen_angle)
{
    PhotoSegmentation seg;
    const cv::Size full = bgr.size();
    seg.limit = fill(full, search_limit_px(rec, cam, specimen_angle));
    const cv::Mat disc_full = fill(full, ring_px(cam, [&](double) { return 0.95 * rec.R2; }, 1.0));
    if (cv::countNonZero(disc_full) < 20)
        throw RefusalError({"disc-too-small", "the disc is only " + std::to_string(cv::countNonZero(disc_full)) + " px in the photo",
                            "photograph the drape larger (closer or zoomed), or check the scale"});
    if (!ov.threshold.empty()) return threshold_segmentation(lab, ov, disc_full, seg);
    Working w = working_regions(bgr, lab, rec, cam, specimen_angle);
    if (const auto region = user_mask(ov, full, disc_full, w)) {
        seg.method = "user mask " + ov.mask_name;
        return finished(seg, lab, *region, 1.0, false);
    }
    const ColourModel cm = colour_model(w, seg);
    check_beyond_limit(rec, w, cm, seg);
    {
        cv::Mat cc(w.ss, CV_8U);
        for (int y = 0; y < w.ss.height; ++y)
            for (int x = 0; x < w.ss.width; ++x) cc.at<uchar>(y, x) = cloth_coloured(w.slab.at<cv::Vec3f>(y, x), cm) ? 255 : 0;
        if (w.ws < 1.0) cv::resize(cc, cc, full, 0, 0, cv::INTER_NEAREST);
        seg.colour_cloth = cc;
    }
    cv::Mat up = grabcut_region(w, cm, seg.clamp_disc, full);
    up |= disc_full;
    seg.method = std::string("GrabCut seeded by the disc and the search limit, ") +
                 (cm.wL < 1 ? "chroma-weighted (L* x " + fmt("%.1f", cm.wL) + ": shadows mostly ignored)" : "full L*a*b*") +
                 (seg.clamp_disc ? ", disc top not cloth-coloured (upper disc?)" : "") + (w.user_fg.empty() ? "" : ", user seeds " + ov.mask_name);
    return finished(seg, lab, up, cm.wL, true);
}

} // namespace drape::capture
