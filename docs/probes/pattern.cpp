// Probe: a preset draped from the record's own measured fold pattern: the lift is the shallowest contour's harmonics 2..K
// (their measured phases and sizes), LIFT_MM at the hem; with a 6th argument n a plain n-fold lift instead. Prints D,
// folds and per measured depth the mean radius and RMS fold amplitude, simulated / measured.
#include "engine/cloth/drape.hpp"
#include "engine/cloth/mesh.hpp"
#include "engine/cloth/solver.hpp"
#include "engine/fabric/preset.hpp"
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>
using namespace drape;
int main(int argc, char** argv) {
    // pattern PRESET CONTOURS.csv LIFT_MM K GRID [n-fold]
    auto p = fabric::load_fabric(argv[1]);
    std::ifstream in(argv[2]);
    std::string line; std::getline(in, line);
    std::map<int, std::vector<double>> R;
    while (std::getline(in, line)) {
        std::stringstream ss(line); std::string a; std::vector<double> v;
        while (std::getline(ss, a, ',')) v.push_back(std::stod(a));
        R[(int)v[0]].push_back(std::hypot(v[2], v[3]));
    }
    const double L = std::atof(argv[3]) * 1e-3;
    const int K = std::atoi(argv[4]);
    const int grid = std::atoi(argv[5]);
    const int nfold = argc > 6 ? std::atoi(argv[6]) : 0;
    const auto& r5 = R.begin()->second;
    double ak[40] = {0}, bk[40] = {0};
    for (int k = 1; k <= K; ++k)
        for (int j = 0; j < 360; ++j) { double th = j * M_PI / 180; ak[k] += r5[j] * std::cos(k * th) / 180; bk[k] += r5[j] * std::sin(k * th) / 180; }
    cloth::DrapeSetup s; s.sample_diameter = 0.3; s.disc_diameter = 0.15; s.grid = grid; s.seed = 1; s.perturbation = 0;
    const auto mat = p.material();
    auto sys = cloth::make_drape_system(mat, s, p.model);
    cloth::Positions X = sys->x;
    const double R1 = 0.15, R2 = 0.075;
    std::vector<double> lift(X.rows()); double mx = 0;
    for (int i = 0; i < X.rows(); ++i) {
        double r = std::hypot(X(i, 0), X(i, 1)), th = std::atan2(X(i, 1), X(i, 0));
        double t = std::max(0.0, r - R2) / (R1 - R2), g = 0;
        if (nfold) g = std::cos(nfold * th);
        else for (int k = 2; k <= K; ++k) g += ak[k] * std::cos(k * th) + bk[k] * std::sin(k * th);
        lift[i] = g * t * t; mx = std::max(mx, std::abs(lift[i]));
    }
    for (int i = 0; i < X.rows(); ++i) X(i, 2) += L * lift[i] / mx;
    cloth::RestOptions ro;
    auto res = cloth::simulate_drape_from(mat, s, X, ro, p.model);
    std::printf("status rest=%d its %ld D %.2f nodes %d E %.6e\n", (int)res.status.converged(), res.status.newton_iterations,
                res.metrics.drape_coefficient_percent, res.metrics.node_count, res.potential_energy);
    for (const auto& sl : res.slices) {
        if (!sl.profile.complete()) continue;
        int d = (int)std::lround(sl.depth_m * 1000);
        if (!R.count(d)) continue;
        double m = 0, q = 0; for (double x : sl.profile.r) m += x; m /= sl.profile.r.size();
        for (double x : sl.profile.r) q += (x - m) * (x - m); q = std::sqrt(q / sl.profile.r.size());
        double mm = 0, qm = 0; for (double x : R[d]) mm += x; mm /= R[d].size();
        for (double x : R[d]) qm += (x - mm) * (x - mm); qm = std::sqrt(qm / R[d].size());
        std::printf("  depth %2d  mean r %.1f / %.1f  rms %.2f / %.2f\n", d, m * 1000, mm, q * 1000, qm);
    }
}
