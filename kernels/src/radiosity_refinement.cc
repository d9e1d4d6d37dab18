#include "lf/kernels/radiosity_refinement.h"

#include <algorithm>
#include <cmath>

#include "lf/kernels/radiosity_display.h"

namespace lf {

namespace {

double L1(const Rgb& c) {
    return std::abs(double(c.r)) + std::abs(double(c.g)) + std::abs(double(c.b));
}

}  // namespace

DiscretisationError EstimateDiscretisationError(const PatchMesh& mesh,
                                                std::span<const Rgb> radiosity) {
    const auto& sides = mesh.sides();
    const auto& patches = mesh.patches();
    DiscretisationError error;
    error.indicator.assign(patches.size(), 0);
    std::vector<double> relative(patches.size(), 0);
    if (sides.empty()) return error;
    // The floor: the scene's area-weighted mean radiosity, in the same norm.
    double power = 0, area = 0;
    for (size_t s = 0; s < sides.size(); ++s) {
        const double a = patches[size_t(sides[s].patch)].area;
        power += a * L1(radiosity[s]);
        area += a;
    }
    const double floor = power / area;
    const std::vector<std::array<Rgb, 3>> corners = SmoothCorners(mesh, radiosity);
    for (size_t s = 0; s < sides.size(); ++s) {
        const Rgb& b = radiosity[s];
        double worst = 0;
        for (const Rgb& c : corners[s]) worst = std::max(worst, L1(c - b));
        // floor > 0 unless all is black, when every difference is 0 too.
        double& e = relative[size_t(sides[s].patch)];
        e = std::max(e, floor > 0 ? worst / (L1(b) + floor) : 0);
    }
    double weighted = 0, weight = 0;
    for (size_t p = 0; p < patches.size(); ++p) {
        const PatchMesh::Patch& patch = patches[p];
        if (patch.sides[0] < 0 && patch.sides[1] < 0) continue;
        // The share of a quarter of level l: its area is the coarse cell's over 4^l.
        error.indicator[p] = std::ldexp(relative[p], -2 * patch.level);
        error.max = std::max(error.max, error.indicator[p]);
        weighted += patch.area * relative[p];
        weight += patch.area;
    }
    error.mean = weighted / weight;
    return error;
}

RefinementStep ChooseRefinement(const PatchMesh& mesh, const DiscretisationError& error,
                                double target, int64_t max_patches) {
    RefinementStep step;
    std::vector<int64_t> candidates;
    for (int64_t p = 0; p < int64_t(error.indicator.size()); ++p) {
        if (!(error.indicator[size_t(p)] > target)) continue;
        ++step.above_target;
        if (mesh.patches()[size_t(p)].level >= kFinestRefinementLevel) {
            ++step.at_finest;
        } else {
            candidates.push_back(p);
        }
    }
    std::stable_sort(candidates.begin(), candidates.end(), [&](int64_t a, int64_t b) {
        return error.indicator[size_t(a)] > error.indicator[size_t(b)];
    });
    const int64_t room = std::max<int64_t>(0, max_patches - int64_t(mesh.patches().size())) / 3;
    if (int64_t(candidates.size()) > room) {
        step.budget_reached = true;
        candidates.resize(size_t(room));
    }
    for (int64_t p : candidates) step.split.push_back(mesh.Cell(p));
    return step;
}

}  // namespace lf
