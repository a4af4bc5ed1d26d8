// The kernel of the surface filter: a Gaussian over a point's surface
// neighbours (surface_neighbours.h) in metres, its sigma a number of lattice
// spacings, cut where it has fallen to about 1 % and normalised to sum to 1.
#pragma once

#include "core/objectspace/surface_neighbours.h"

#include <cstdint>
#include <vector>

namespace modestack::objectspace {

/// Kernels are cut at this many sigmas (weight e^-4.5 ≈ 1 % there).
inline constexpr double kReachInSigmas = 3.0;

/// The weights of p's first neighbours (p itself first, then nearest first, as
/// neighbours.ids(p) lists them) under a Gaussian of sigma `width` spacings of
/// `spacing` metres, summing to 1. The neighbours must reach kReachInSigmas
/// sigmas.
void gaussian_weights(const SurfaceNeighbours& neighbours, std::int64_t p, double width, double spacing,
                      std::vector<double>& weights);

} // namespace modestack::objectspace
