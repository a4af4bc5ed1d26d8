// Which pixels the denoiser is unsure of ([0091], [0093]): each pixel gets a
// score = its estimated relative error, the largest over its channels of
// sigma / sqrt(value² + floor²), with a floor so that dark pixels (where any
// absolute error looks large relative to the value) are judged on an absolute
// scale — the same floor² = 0.01 as the project's relMSE, so that a high score
// means a high contribution to relMSE. Pixels are chosen either above a fixed
// score (--threshold) or as the top P % of every pixel of the shot (--budget):
// a shot-wide histogram of log scores gives that threshold with memory that
// does not grow with the shot, and concentrates the budget on the frames that
// need it (a passing object) instead of spreading it evenly over the frames.
// Lone selected pixels are dropped (see drop_isolated_pixels).
//
// Or by gain per cost (--by-gain, for a re-render by modestack itself): a
// pixel's score is the relMSE its re-render would remove, sigma² minus the
// variance of the blend (blend.h) with a re-render whose variance is the
// input's scaled to the refine spp, per channel over value² + floor². A pixel
// re-rendered at S spp costs S samples. The same samples spent on the whole
// shot as more input spp would lower its relMSE E by about E / s per sample a
// pixel (at s input spp; a denoised shot's error falls as 1/spp where noise
// rules it), so a pixel pays for its re-render when its gain is at least
// (S / s) · E, E the relMSE that sigma predicts for the shot. Where bias rules
// the error more spp everywhere buys less than that, and the rule re-renders
// no more than it should. It is only as good as sigma's ranking of the error
// (bench/results/refine_gain.md).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace modestack::refine {

/// The relMSE floor: a value of 0.1 or less is judged on an absolute scale.
inline constexpr float kDefaultDarkFloor = 0.1f;

/// Writes one score per pixel into `scores`: max over the `channels` of
/// sigma / sqrt(value² + dark_floor²). `value` and `sigma` are `pixels` ×
/// `channels` interleaved floats. Non-finite sigma counts as infinitely unsure.
void relative_error_scores(const float* value, const float* sigma, std::size_t pixels, int channels,
                           float dark_floor, float* scores);

/// Writes one score per pixel into `gains`: the relMSE a re-render removes,
/// the channel mean of (sigma² − the blend's variance) / (value² + dark_floor²)
/// with the re-render's variance = `input_variance` × `variance_scale` (the
/// input's variance of the mean, times input spp / refine spp), the blend's
/// variance as blend_refined makes it with weight 1. Non-finite sigma or
/// variance counts as an infinite gain (as in relative_error_scores).
void refine_gains(const float* value, const float* sigma, const float* input_variance, double variance_scale,
                  std::size_t pixels, int channels, float dark_floor, float* gains);

/// The least gain a re-render at `refine_spp` pays for on a shot rendered at
/// `input_spp` whose predicted relMSE is `shot_relative_mse` (see above):
/// (refine_spp / input_spp) · shot_relative_mse; +infinity (nothing) when that
/// is not positive.
float gain_threshold(double shot_relative_mse, int input_spp, int refine_spp);

/// A histogram of scores over a whole shot, for the --budget threshold. Bins are
/// logarithmic (ratio 1.0017 between edges) from 1e-6 to 1e6; scores outside go
/// to the end bins. Counting is exact, so the result is independent of order.
class ScoreHistogram {
public:
    ScoreHistogram();
    /// Counts `count` scores.
    void add(const float* scores, std::size_t count);
    /// Scores counted so far.
    std::int64_t total() const { return m_total; }
    /// The lowest threshold that selects (with `score >= threshold`) at most
    /// `fraction` of the scores counted, up to one bin's width: the lower edge of
    /// the bin where the count from the top reaches fraction·total. Returns
    /// +infinity for fraction ≤ 0 (nothing) and 0 for fraction ≥ 1 (everything
    /// with a positive score).
    float threshold_for_fraction(double fraction) const;

private:
    std::vector<std::int64_t> m_counts;
    std::int64_t m_total = 0;
};

/// Marks pixels whose score is ≥ `threshold` and > 0 with 1, others with 0.
std::vector<std::uint8_t> select_pixels(const float* scores, std::size_t pixels, float threshold);

/// Unselects pixels of a `width` × `height` selection with fewer than
/// `min_neighbours` selected 8-neighbours. Why: content the modes miss (an object,
/// a shadow) is coherent over several pixels, while a lone pixel above the
/// threshold is noise in the sigma estimate; growing and feathering it would cost
/// a whole disc of re-rendered pixels (measured on `orbit` at 320×240: a 2 %
/// selection became 33 % of the pixels to re-render). Decided on the input
/// selection, so the result does not depend on the scan order.
void drop_isolated_pixels(std::vector<std::uint8_t>& selection, int width, int height,
                          int min_neighbours = 2);

} // namespace modestack::refine
