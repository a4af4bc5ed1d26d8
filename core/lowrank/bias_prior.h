// Sigma's bias term by empirical Bayes (docs/design.md, "Sigma's bias term").
// The windowed residual mean μ of a sample is its missed content b plus noise
// of variance τ² (lowrank/confidence.h). The old term max(0, μ² − τ²) is
// unbiased for b², but on a sample with no bias its positive part still averages
// about 0.48·τ²: where a wide mode filter keeps a hundredth of that as noise,
// sigma was mostly this term's noise (too wide on indirect light). Here b/τ is
// given a prior learnt from the samples themselves, a mixture of zero-mean
// Gaussians of fixed variances κ_k·τ² with weights fitted by EM to the counts
// of t² = μ²/τ² of one image row over every frame (the nonparametric maximum
// likelihood estimate on a fixed grid). Its posterior mean
//   E[b²/τ² | t] = Σ_k P(k | t) · (g_k² · t² + g_k),  g_k = κ_k / (1 + κ_k),
// is near 0 for t within the noise of a row whose samples are mostly unbiased,
// and near t² where a row holds much missed content. A row, not the shot: the
// prior follows where the model fails (a moving shadow's rows), and each row's
// counts are exact integers over its own samples, so every band plan, thread
// count and farm split gives the same bits.
#pragma once

#include <array>
#include <cstdint>
#include <cstring>
#include <vector>

namespace modestack::lowrank {

/// Bins of t² = μ²/τ²: one for t² below 2^kLowestOctave (and 0), kBinsPerOctave
/// per octave up to 2^kHighestOctave, one above (and infinite t², τ² = 0).
inline constexpr int kBiasLowestOctave = -20;
inline constexpr int kBiasHighestOctave = 24;
inline constexpr int kBiasBinsPerOctave = 4;
inline constexpr int kBiasBins = (kBiasHighestOctave - kBiasLowestOctave) * kBiasBinsPerOctave + 2;

/// Counts of t² per bin for one image row.
using BiasRatioCounts = std::array<std::int64_t, kBiasBins>;

/// The bin of t² (NaN: the lowest, as t = 0/0 carries no evidence of bias).
/// Read from the double's bits (it runs once or twice per sample and frame):
/// the exponent is the octave, the mantissa against the fractions of 2^(1/4),
/// 2^(1/2), 2^(3/4) is the quarter.
inline int bias_bin(double ratio)
{
    std::uint64_t bits;
    std::memcpy(&bits, &ratio, sizeof bits);
    const int field = static_cast<int>(bits >> 52); // sign and exponent; t² is never negative
    const std::uint64_t mantissa = bits & ((std::uint64_t{1} << 52) - 1);
    if (field == 0x7ff && mantissa != 0)
        return 0;       // NaN
    if (field >= 0x800) // a negative number: no bias either
        return 0;
    const int octave = field - 1023;
    if (octave < kBiasLowestOctave)
        return 0;
    if (octave >= kBiasHighestOctave)
        return kBiasBins - 1;
    // The mantissa fields of 2^(1/4), 2^(1/2) and 2^(3/4) as doubles.
    constexpr std::uint64_t kQuarter = 0x306FE0A31B715ULL, kHalf = 0x6A09E667F3BCDULL,
                            kThreeQuarters = 0xAE89F995AD3ADULL;
    const int step = (mantissa >= kQuarter) + (mantissa >= kHalf) + (mantissa >= kThreeQuarters);
    return 1 + (octave - kBiasLowestOctave) * kBiasBinsPerOctave + step;
}

/// The median of the counted t² (the centre of its bin; 0 without counts).
double bias_ratio_median(const BiasRatioCounts& counts);

/// The posterior of one row as two factors per bin: E[b² | μ, τ] =
/// slope[bin] · μ² + offset[bin] · τ² (written so, τ² = 0 gives μ², never 0 · ∞).
struct BiasPosterior {
    std::array<float, kBiasBins> slope{};
    std::array<float, kBiasBins> offset{};
};

/// Fits the prior's weights to `counts` (EM, a fixed number of steps from a
/// fixed start: deterministic) and returns the posterior factors at each
/// bin's centre. No counts: slope 1, offset 0 (the bias is μ²).
BiasPosterior fit_bias_posterior(const BiasRatioCounts& counts);

/// The prior's weights after fitting (for tests and reports), one per variance
/// of bias_prior_variances().
std::vector<double> fit_bias_prior(const BiasRatioCounts& counts);
/// κ_k: the variances of the prior's components, in units of τ² (0 first).
const std::vector<double>& bias_prior_variances();

} // namespace modestack::lowrank
