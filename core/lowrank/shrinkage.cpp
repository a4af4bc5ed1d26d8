#include "core/lowrank/shrinkage.h"

#include "core/common/error.h"

#include <algorithm>
#include <cmath>

namespace modestack::lowrank {

double optimal_shrink_frobenius(double y, double beta)
{
    if (y < 1 + std::sqrt(beta))
        return 0.0;
    const double a = y * y - beta - 1;
    return std::sqrt(std::max(0.0, a * a - 4 * beta)) / y;
}

std::vector<double> optimal_shrinkage_factors(const Basis& basis, double noise_sigma, int kept_modes)
{
    if (kept_modes < 0 || kept_modes > basis.modes())
        throw internal_error("shrinkage: rank outside the basis");
    std::vector<double> factors(static_cast<std::size_t>(kept_modes), 1.0);
    if (!(noise_sigma > 0) || basis.rows <= 0)
        return factors;
    const double rows = static_cast<double>(basis.rows), frames = basis.frames();
    const double large = std::max(rows, frames), beta = std::min(rows, frames) / large;
    const double unit = noise_sigma * std::sqrt(large); // the noise bulk's edge is unit · (1 + sqrt(β))
    for (int j = 0; j < kept_modes; ++j) {
        const double value = basis.singular_values[j];
        factors[static_cast<std::size_t>(j)] =
            value > 0 ? std::clamp(optimal_shrink_frobenius(value / unit, beta) * unit / value, 0.0, 1.0)
                      : 0.0;
    }
    return factors;
}

} // namespace modestack::lowrank
