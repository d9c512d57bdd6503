#include "engine/capture/segmentation.hpp"

#include "engine/capture/pixels.hpp"
#include "engine/core/error.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

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
    for (double r = rec.R1 + 0.035; r <= rec.R1 + 0.06; r += 0.005)
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

} // namespace drape::capture
