// The Gaussian kernel over surface neighbours (see surface_kernel.h).
#include "core/objectspace/surface_kernel.h"

namespace modestack::objectspace {

SurfaceGaussian surface_gaussian(double width, double spacing)
{
    const double sigma = width * spacing, reach = kReachInSigmas * sigma;
    return {1.0 / (2 * sigma * sigma), static_cast<float>(reach * reach)};
}

} // namespace modestack::objectspace
