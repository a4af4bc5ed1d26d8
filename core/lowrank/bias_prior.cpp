#include "core/lowrank/bias_prior.h"

#include <algorithm>
#include <cmath>

namespace modestack::lowrank {
namespace {

// EM's steps, a fixed count so that the bits depend on no tolerance, from a
// start of "nine samples in ten unbiased" (the rest spread evenly). The weights
// of the small variances share their samples with the noise and move slowly
// away from any start: from equal weights, 200 steps left a posterior mean of
// 0.058·τ² on pure noise, from this start 0.005·τ²; a bias the data show pulls
// its weight up within a few steps from either start.
constexpr int kSteps = 200;
constexpr double kUnbiasedStart = 0.9;

// Bin i's t²: its centre in log2 (the lowest bin 0, the highest its lower edge).
double bin_ratio(int bin)
{
    if (bin == 0)
        return 0;
    if (bin == kBiasBins - 1)
        return std::ldexp(1.0, kBiasHighestOctave);
    return std::exp2(kBiasLowestOctave + (bin - 0.5) / kBiasBinsPerOctave);
}

// The likelihood of each bin under each component, scaled per bin to a largest
// value of 1 (the scale cancels in every responsibility): [bin][component].
struct Likelihoods {
    std::vector<double> values;
    std::vector<double> shrink; // g_k = κ_k / (1 + κ_k)
    Likelihoods()
    {
        const std::vector<double>& variances = bias_prior_variances();
        const std::size_t components = variances.size();
        values.resize(kBiasBins * components);
        for (int bin = 0; bin < kBiasBins; ++bin) {
            const double ratio = bin_ratio(bin);
            double* row = &values[static_cast<std::size_t>(bin) * components];
            double largest = -INFINITY;
            for (std::size_t k = 0; k < components; ++k) {
                const double spread = 1 + variances[k];
                row[k] = -0.5 * ratio / spread - 0.5 * std::log(spread);
                largest = std::max(largest, row[k]);
            }
            for (std::size_t k = 0; k < components; ++k)
                row[k] = std::exp(row[k] - largest);
        }
        for (double variance : variances)
            shrink.push_back(variance / (1 + variance));
    }
};

const Likelihoods& likelihoods()
{
    static const Likelihoods table;
    return table;
}

// Responsibilities of bin `bin` under `weights`, into `out`; false where every
// component gives it zero weight.
bool responsibilities(const Likelihoods& table, int bin, const std::vector<double>& weights, double* out)
{
    const std::size_t components = weights.size();
    const double* row = &table.values[static_cast<std::size_t>(bin) * components];
    double total = 0;
    for (std::size_t k = 0; k < components; ++k)
        total += out[k] = row[k] * weights[k];
    if (!(total > 0))
        return false;
    for (std::size_t k = 0; k < components; ++k)
        out[k] /= total;
    return true;
}

} // namespace

double bias_ratio_median(const BiasRatioCounts& counts)
{
    std::int64_t total = 0;
    for (std::int64_t count : counts)
        total += count;
    std::int64_t below = 0;
    for (int bin = 0; bin < kBiasBins; ++bin) {
        below += counts[static_cast<std::size_t>(bin)];
        if (total > 0 && 2 * below >= total)
            return bin_ratio(bin);
    }
    return 0;
}

const std::vector<double>& bias_prior_variances()
{
    // 0, then 2^-4 … 2^16: from a shade of the noise to far beyond it.
    static const std::vector<double> variances = [] {
        std::vector<double> result{0.0};
        for (int e = -4; e <= 16; ++e)
            result.push_back(std::ldexp(1.0, e));
        return result;
    }();
    return variances;
}

std::vector<double> fit_bias_prior(const BiasRatioCounts& counts)
{
    const Likelihoods& table = likelihoods();
    const std::size_t components = bias_prior_variances().size();
    std::vector<double> weights(components, (1 - kUnbiasedStart) / static_cast<double>(components));
    std::vector<double> next(components), share(components);
    weights[0] += kUnbiasedStart;
    double total = 0;
    for (std::int64_t count : counts)
        total += static_cast<double>(count);
    if (total <= 0)
        return weights;
    for (int step = 0; step < kSteps; ++step) {
        std::fill(next.begin(), next.end(), 0.0);
        for (int bin = 0; bin < kBiasBins; ++bin) {
            if (counts[static_cast<std::size_t>(bin)] == 0 ||
                !responsibilities(table, bin, weights, share.data()))
                continue;
            const double count = static_cast<double>(counts[static_cast<std::size_t>(bin)]);
            for (std::size_t k = 0; k < components; ++k)
                next[k] += count * share[k];
        }
        for (std::size_t k = 0; k < components; ++k)
            weights[k] = next[k] / total;
    }
    return weights;
}

BiasPosterior fit_bias_posterior(const BiasRatioCounts& counts)
{
    BiasPosterior posterior;
    posterior.slope.fill(1.0f);
    bool any = false;
    for (std::int64_t count : counts)
        any = any || count > 0;
    if (!any)
        return posterior;
    const Likelihoods& table = likelihoods();
    const std::vector<double> weights = fit_bias_prior(counts);
    std::vector<double> share(weights.size());
    for (int bin = 0; bin + 1 < kBiasBins; ++bin) {
        double slope = 1, offset = 0;
        if (responsibilities(table, bin, weights, share.data())) {
            slope = offset = 0;
            for (std::size_t k = 0; k < weights.size(); ++k) {
                slope += share[k] * table.shrink[k] * table.shrink[k];
                offset += share[k] * table.shrink[k];
            }
        }
        posterior.slope[static_cast<std::size_t>(bin)] = static_cast<float>(slope);
        posterior.offset[static_cast<std::size_t>(bin)] = static_cast<float>(offset);
    }
    // Beyond 2^24 noise explains nothing: the bias is μ² (and τ² = 0 gives μ² exactly).
    posterior.slope.back() = 1.0f;
    posterior.offset.back() = 0.0f;
    return posterior;
}

} // namespace modestack::lowrank
