// The Gaussian kernel over surface neighbours (see surface_kernel.h).
#include "core/objectspace/surface_kernel.h"

#include <cmath>

namespace modestack::objectspace {

void gaussian_weights(const SurfaceNeighbours& neighbours, std::int64_t p, double width, double spacing,
                      std::vector<double>& weights)
{
    const float* d2 = neighbours.distances_squared(p);
    const double sigma = width * spacing, reach = kReachInSigmas * sigma;
    weights.assign(1, 1.0); // p itself
    double total = 1;
    for (std::int64_t n = 1; n < neighbours.size(p) && d2[n] <= reach * reach; ++n) {
        weights.push_back(std::exp(-0.5 * d2[n] / (sigma * sigma)));
        total += weights.back();
    }
    for (double& w : weights)
        w /= total;
}

} // namespace modestack::objectspace
