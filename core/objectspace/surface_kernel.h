// The kernel of the surface filter: a Gaussian over a point's surface
// neighbours (surface_cells.h) in metres, its sigma a number of lattice
// spacings, cut where it has fallen to about 1 % and normalised to sum to 1
// (the point itself has weight 1 before normalising).
#pragma once

#include "core/objectspace/surface_cells.h"

#include <cmath>
#include <cstdint>
#include <vector>

namespace modestack::objectspace {

/// Kernels are cut at this many sigmas (weight e^-4.5 ≈ 1 % there).
inline constexpr double kReachInSigmas = 3.0;

/// One Gaussian, in metres.
struct SurfaceGaussian {
    double inverse_two_sigma_squared = 0;
    float reach_squared = 0;
    /// Unnormalised weight of a neighbour `distance_squared` m² away (0 beyond the reach).
    double weight(float distance_squared) const
    {
        return distance_squared <= reach_squared ? std::exp(-distance_squared * inverse_two_sigma_squared)
                                                 : 0.0;
    }
};

/// The Gaussian of sigma `width` spacings of `spacing` metres (width > 0).
SurfaceGaussian surface_gaussian(double width, double spacing);

/// Calls each(q, weight) for p and every neighbour within the Gaussian's reach
/// with its unnormalised weight (p's is 1), and returns their sum: divide by it
/// to normalise.
template <class Each>
double weigh_neighbours(const SurfaceGaussian& gaussian, std::int64_t p,
                        const std::vector<SurfaceNeighbour>& neighbours, Each&& each)
{
    double total = 0;
    for (const SurfaceNeighbour& neighbour : neighbours) {
        const double weight = neighbour.id == p ? 1.0 : gaussian.weight(neighbour.distance_squared);
        if (weight == 0)
            continue;
        total += weight;
        each(neighbour.id, weight);
    }
    return total;
}

} // namespace modestack::objectspace
