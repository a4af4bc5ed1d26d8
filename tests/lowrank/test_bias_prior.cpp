// Sigma's bias prior (core/lowrank/bias_prior.h): the bins of t², the EM fit of
// the prior's weights on samples drawn from a known mixture, and a posterior
// that is near zero on noise and near t² on a bias far beyond it.
#include "core/lowrank/bias_prior.h"
#include "core/lowrank/randomized_svd.h"

#include <doctest/doctest.h>

#include <cmath>

using namespace modestack::lowrank;

namespace {

// Counts of t² for `samples` draws of t = b/τ + noise, b/τ ~ N(0, κ) on a
// `share` of them (0 on the rest).
BiasRatioCounts mixture_counts(int samples, double share, double variance, std::uint64_t seed)
{
    const Eigen::MatrixXd draws = gaussian_matrix(samples, 2, seed);
    BiasRatioCounts counts{};
    for (int i = 0; i < samples; ++i) {
        const bool biased = i < share * samples;
        const double t = draws(i, 0) + (biased ? std::sqrt(variance) * draws(i, 1) : 0.0);
        ++counts[static_cast<std::size_t>(bias_bin(t * t))];
    }
    return counts;
}

double weight_from(const std::vector<double>& weights, double lowest_variance)
{
    double sum = 0;
    for (std::size_t k = 0; k < weights.size(); ++k)
        if (bias_prior_variances()[k] >= lowest_variance)
            sum += weights[k];
    return sum;
}

} // namespace

TEST_CASE("bias bins: quarter octaves of t², zero and NaN lowest, infinity highest")
{
    CHECK(bias_bin(0.0) == 0);
    CHECK(bias_bin(std::nan("")) == 0);
    CHECK(bias_bin(std::ldexp(1.0, kBiasLowestOctave) * 0.99) == 0);
    CHECK(bias_bin(std::ldexp(1.0, kBiasLowestOctave)) == 1);
    CHECK(bias_bin(std::ldexp(1.0, kBiasHighestOctave)) == kBiasBins - 1);
    CHECK(bias_bin(INFINITY) == kBiasBins - 1);
    // 1 = 2^0 opens its octave's first bin; 2^(1/4) the next one.
    const int one = 1 + (0 - kBiasLowestOctave) * kBiasBinsPerOctave;
    CHECK(bias_bin(1.0) == one);
    CHECK(bias_bin(std::nextafter(std::exp2(0.25), 0.0)) == one);
    CHECK(bias_bin(std::exp2(0.25) * (1 + 1e-12)) == one + 1);
    CHECK(bias_bin(1.999) == one + 3);
    CHECK(bias_bin(2.0) == one + 4);
    int previous = 0;
    for (double ratio = 1e-7; ratio < 1e8; ratio *= 1.01) {
        const int bin = bias_bin(ratio);
        CHECK_MESSAGE(bin >= previous, "t² " << ratio);
        previous = bin;
    }
}

TEST_CASE("the bias prior's fit recovers the share of a known mixture")
{
    for (const double share : {0.0, 0.05, 0.3}) {
        const std::vector<double> weights = fit_bias_prior(mixture_counts(200000, share, 64.0, 11));
        const double biased = weight_from(weights, 8.0);
        MESSAGE("share " << share << ": weight at variances >= 8 " << biased);
        CHECK(std::abs(biased - share) <= 0.02);
    }
}

TEST_CASE("the bias posterior: about zero on pure noise, about t² far beyond it, calibrated on a mixture")
{
    // Pure noise: the old term max(0, t² − 1) averages 0.48 here.
    const BiasRatioCounts noise = mixture_counts(200000, 0.0, 0.0, 3);
    const BiasPosterior on_noise = fit_bias_posterior(noise);
    double mean = 0, old = 0, total = 0;
    for (int bin = 0; bin < kBiasBins; ++bin) {
        const double count = static_cast<double>(noise[static_cast<std::size_t>(bin)]);
        if (count == 0)
            continue;
        const double ratio = bin == 0 ? 0 : std::exp2(kBiasLowestOctave + (bin - 0.5) / kBiasBinsPerOctave);
        mean += count * (on_noise.slope[static_cast<std::size_t>(bin)] * ratio +
                         on_noise.offset[static_cast<std::size_t>(bin)]);
        old += count * std::max(0.0, ratio - 1);
        total += count;
    }
    MESSAGE("pure noise: posterior mean of b²/τ² " << mean / total << ", old term " << old / total);
    // (EM's fixed steps leave a little weight on the smallest variances.)
    CHECK(mean / total < 0.2 * (old / total));
    CHECK(old / total > 0.4);

    // A 10 % share of bias of variance 64 τ²: the posterior's mean over all samples
    // is the true mean b² (6.4 τ²), and a sample at t² = 400 keeps nearly all of it.
    const Eigen::MatrixXd draws = gaussian_matrix(200000, 2, 7);
    BiasRatioCounts counts{};
    std::vector<double> ratios;
    double true_bias = 0;
    for (int i = 0; i < 200000; ++i) {
        const double b = i % 10 == 0 ? 8.0 * draws(i, 1) : 0.0;
        const double t = draws(i, 0) + b;
        true_bias += b * b;
        ratios.push_back(t * t);
        ++counts[static_cast<std::size_t>(bias_bin(t * t))];
    }
    const BiasPosterior posterior = fit_bias_posterior(counts);
    double estimated = 0;
    for (double ratio : ratios) {
        const auto bin = static_cast<std::size_t>(bias_bin(ratio));
        estimated += posterior.slope[bin] * ratio + posterior.offset[bin];
    }
    MESSAGE("mixture: mean posterior b²/τ² " << estimated / ratios.size() << ", true "
                                             << true_bias / ratios.size());
    CHECK(std::abs(estimated / true_bias - 1) < 0.05);
    const auto far = static_cast<std::size_t>(bias_bin(400.0));
    const double at_far = posterior.slope[far] * 400.0 + posterior.offset[far];
    CHECK(at_far > 0.95 * 399);
    CHECK(at_far < 1.05 * 400);
}

TEST_CASE("the bias posterior of a row without counts, and of τ² = 0, is μ²")
{
    const BiasPosterior empty = fit_bias_posterior(BiasRatioCounts{});
    for (int bin = 0; bin < kBiasBins; ++bin) {
        CHECK(empty.slope[static_cast<std::size_t>(bin)] == 1.0f);
        CHECK(empty.offset[static_cast<std::size_t>(bin)] == 0.0f);
    }
    const BiasPosterior fitted = fit_bias_posterior(mixture_counts(1000, 0.1, 16.0, 5));
    CHECK(fitted.slope.back() == 1.0f); // infinite t²: τ² = 0 and μ ≠ 0
    CHECK(fitted.offset.back() == 0.0f);
}
