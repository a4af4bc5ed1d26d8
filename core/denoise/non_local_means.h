// Non-local means of one frame's input (Buades et al. 2005, with the variance-
// cancelled patch distance of Rousselle, Knaus & Zwicker 2012): a pixel becomes
// the weighted mean of the pixels within kNonLocalSearch whose 3×3 patch looks
// like its own, given the noise. Unlike a Gaussian it keeps a hard shadow's edge,
// so where the temporal rebuild is rejected it does not blur light into the shadow.
//
// Its weights depend on the noisy input, so its SURE needs the divergence with
// the weights' derivative (Van De Ville & Kocher 2009); the first-order term,
// from the centre pixel's own patch, is given here (exact within a few % on
// Gaussian noise). Even so its SURE is only unbiased for Gaussian noise: on
// rendered noise (a few spp: discrete, heavy tailed) it came out far below the
// true error on every benchmark shot (bench/results/estimators.md, section 5),
// so the choice never lets it beat the rebuild on its own risk, and its sigma is
// the one of the candidate it displaces (estimator_choice.h).
#pragma once

#include <vector>

namespace modestack::denoise {

inline constexpr int kNonLocalSearch = 3; ///< search window radius (7×7; 11×11 measured no better)
inline constexpr int kNonLocalReach = kNonLocalSearch + 1; ///< rows of input beyond the pixel's (the patch)

/// One frame's input rows, laid out [row][x][channel] from `input_begin`.
struct NonLocalInput {
    int width = 0, height = 0, channels = 0;
    const float* input = nullptr; ///< rows covering the pixel's row ± kNonLocalReach (clipped to the image)
    int input_begin = 0;
};

/// The filter at pixel (x, y), given the noise variance of its samples
/// (`variance`, one per channel): per channel its value and its divergence
/// ∂value/∂input at the same sample. `scratch` is the caller's, reused from pixel
/// to pixel. Deterministic: summed in a fixed order.
void non_local_means(const NonLocalInput& frame, int x, int y, const float* variance, float* value,
                     float* divergence, std::vector<double>& scratch);

} // namespace modestack::denoise
