// A per-pixel choice among estimators of a frame (docs/design.md, "Choosing an
// estimator per pixel"): the temporal rebuild, the (cleaned) input and Gaussian
// blurs of the input, judged by Stein's unbiased risk estimate (SURE) pooled over
// a window. Where the temporal model fails (a shadow that sweeps, an object seen
// in a few frames) the rebuild is worse than its own input; the risk estimate
// sees it and takes what is better there, so the output is never knowingly
// worse than the input, and sigma becomes the estimated error of what is written.
//
// For a sample y = x + n with noise variance v and an estimator f whose
// derivative at the sample is w = ∂f/∂y (its divergence), SURE
//   S = (f − y)² − v + 2·v·w
// is an unbiased estimate of (f − x)². w is the rebuild's kept noise h (the
// leverage; under the mode filter its kept-noise gain Σ V²·Σa² stands in for the
// divergence Σ V²·a_pp, which it is below: a known simplification), a
// Gaussian's centre weight, 1 for the input (S = v). y is the input as read (NaN/Inf cleaned, not fireflies:
// the temporal firefly clamp hides the rebuild's errors where the light moves). v is the windowed mean of the
// squared 4-neighbour high-pass of the residual y − rebuild, divided by 1 + 1/k for k neighbours: a mean (not
// a median), so that v is the variance of the very samples SURE sees; at most
// the same windowed power of y's own high-pass (each is the noise plus
// something: the picture's edges, or the misfit of a rebuild that is far off,
// which would raise v where the rebuild is wrong and hide it). Noise
// that repeats from frame to frame (repeating_noise.h) is not in the residual:
// where it is counted, v gains share × the same windowed power of the input's
// own high-pass, and the rebuild, which keeps that part whole, takes it with
// slope 1 in its SURE, its sigma and the per-pixel test in time.
//
// The rebuild is kept unless another estimator's pooled SURE is lower by more
// than z standard errors of the window mean of the per-pixel difference. SURE of
// a strong denoiser is a small difference of two large noisy numbers; an argmin
// would pick by chance wherever risks are close (measured in
// bench/results/estimators.md: it made the indirect light 2–3× worse). Of the
// blurs that pass, the one with the larger pooled gain is taken (their risks
// are close: the 3×3 SURE picked between them by chance); the input, if it
// passes, takes its place where its SURE over the 3×3 pixels around is lower
// (the narrow window sees a blur's bias at an edge).
// The window test cannot see a failure of a few pixels: a gain carried by k
// pixels of the window scores about √k standard errors, whatever its size (a
// firefly is such a gain too). One kind of narrow failure can be told from
// fireflies: the input far *below* the rebuild (a thin sliver of a moving hard
// shadow that the rebuild fills with light seen in other frames). Render noise
// has a bounded lower tail (values are not negative, fireflies are bright), so
// where the 3×3 mean of min(input − rebuild, 0) lies below its mean under
// Gaussian noise of scale s (−0.399·s) by more than z (default 6) of its
// standard error (0.584·s/√9), the rebuild is not taken there; the candidate
// with the least 3×3 SURE is. s is the root of sigma's noise level s², pooled
// over every frame, times this frame's noise factor (frame_noise.h: a frame lit
// by a point light alone is far cleaner than the shot's mean). s² is a mean of
// squares, so a heavy upper tail widens it: the test is conservative
// where the noise is heavy-tailed (on indirect light it changed 0.03 % of the
// pixels of one benchmark shot and none of six others).
// Both window tests miss a failure at single pixels whose input is far
// cleaner than s says (the edge of a moving hard shadow lit by a point light).
// There the input's spread in time (temporal_spread.h: its frame-to-frame
// differences at the pixel and its row neighbours over the 4 frames on the
// quieter side, as they are and less that side's trend) is the evidence: the
// value the tests above took, the rebuild or a blur, gives way to the input
// where, by either spread, the input lies below it by more than z·√(b·v̂), or
// above it by more than (r + z·√b)·√v̂, with z the one-sided test's, b the
// spread's upper-bound factor (spread_bound) and r a lone sample's reach
// (lone_sample_reach, a hard bound in spreads): a lone firefly cannot pass
// above. The input, not the least
// 3×3 SURE: next to a bright edge a blur's SURE falls far below its error, and
// a blur that won the window test there carries the edge's light onto a dim
// neighbour as far as the rebuild would.
// A kept rebuild also gives way to the input where its misfit lasts
// (temporal_misfit.h): the residual input − rebuild at the pixel keeps its sign
// and size over the frames on one side beyond Student's t, and the engine's
// own sigma² of the rebuild is at least the residuals' scatter (the rebuild
// admits it is no better than the input's noise; alone, the test took runs of
// bright indirect paths for misfits).
// Non-local means of the input (non_local_means.h) keeps the hard edges a
// Gaussian blurs, but its SURE is biased low on rendered noise, so it is never
// evidence against the rebuild or any linear candidate: where the rebuild has
// been rejected (by a linear candidate's significant gain or by the one-sided
// test) and the candidate taken shows a significant bias (its pooled SURE above
// its variance part, as for sigma), it takes that candidate's place if its 3×3
// SURE is lower, and keeps that candidate's sigma. Letting it replace unbiased
// candidates too made the indirect light 2–28 % worse. It is computed only
// around those pixels.
// Sigma of the chosen estimator is its known variance part (the rebuild: the
// engine's sigma²; a Gaussian: v·Σw²; the input: v) plus the bias the variance
// part misses: the rebuild's pooled SURE excess where it is z standard errors
// above it, a blur's whenever positive (a blur's bias is of the order of the
// pooled SURE's noise, and the gate left the blurs' sigma short).
#pragma once

#include "core/denoise/repeating_noise.h"
#include "core/lowrank/confidence.h"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace modestack::denoise {

/// The estimators a choice can take, in the order reports list them.
enum class Estimator { Rebuild, Input, Gauss1, Gauss2, NonLocal };
inline constexpr int kEstimators = 5;

/// The name users write: "rebuild", "input", "gauss1", "gauss2", "nlmeans".
std::string estimator_name(Estimator estimator);

/// Settings of the choice (--estimators).
struct EstimatorOptions {
    bool input = false;        ///< the input itself is a candidate
    bool spatial = false;      ///< Gaussian blurs of the input (1 and 2 px) are candidates
    bool non_local = false;    ///< non-local means may replace a biased candidate taken (not the rebuild)
    double significance = 2.0; ///< z: standard errors a switch away from the rebuild needs
    int radius = 3;            ///< risk window radius (3: 7×7 pixels)
    /// z of the one-sided test that rejects the rebuild where the input lies far
    /// below it over 3×3 pixels, in the noise's own scale, and of the per-pixel
    /// test in the input's spread in time (see the file comment).
    double below_significance = 6.0;
    bool enabled() const { return input || spatial || non_local; }
};

/// Parses a comma-separated list of "rebuild", "input", "spatial", "nlmeans" (rebuild is
/// always there); throws a usage error naming a bad entry.
EstimatorOptions parse_estimators(const std::string& list);

/// Rows beyond a band's own rows that the choice needs rebuilt (with their
/// sigma and kept noise): the risk window of the high-pass's window.
int estimator_rebuilt_reach(const EstimatorOptions& options);
/// Frames on each side of a frame whose input the choice reads (the per-pixel
/// test's spread, temporal_spread.h, and the lasting misfit's frames and their
/// rebuilds, temporal_misfit.h; 0 without the input as a candidate).
int estimator_frame_reach(const EstimatorOptions& options);
/// Rows beyond a band's own rows that the choice needs of the input.
int estimator_input_reach(const EstimatorOptions& options);

/// One frame's rows for the choice. Rows are image rows; every plane is laid
/// out [row][x][channel] from its first row.
struct ChoiceFrame {
    lowrank::ImageBandShape image; ///< the whole image's width, height and channels
    const float* input = nullptr;  ///< the cleaned input, rows [input_begin, input_end)
    int input_begin = 0, input_end = 0;
    /// The rebuild, the engine's sigma and the kept noise h per sample, rows
    /// [rebuilt_begin, rebuilt_end); kept_noise null: `leverage` everywhere.
    const float* rebuilt = nullptr;
    const float* sigma = nullptr;
    const float* kept_noise = nullptr;
    /// Per pixel of the same rows, the input's noise scale: the channel mean of
    /// √s², s² pooled over the shot as for sigma (noise_scale_rows; the same for
    /// every frame). Null: no test of the input below the rebuild.
    const float* noise_scale = nullptr;
    /// This frame's noise level over the shot's (frame_noise.h): the
    /// one-sided test takes noise_scale times this.
    double noise_factor = 1;
    /// The share of the input's noise that repeats from frame to frame
    /// (repeating_noise.h; 0: none counted). The rebuild keeps that part whole
    /// and the residual's v cannot see it: the choice adds share × the windowed
    /// power of the input's own high-pass to every candidate's noise variance.
    double repeating_share = 0;
    /// Whether the noise was found to repeat at all (counted or not): the
    /// rebuild can then remove only the part that is new in each frame, and
    /// where it does not beat the input by the window test the input is taken.
    bool noise_repeats = false;
    /// The share of the input's noise that repeats but is not counted in the
    /// risks (RepeatingNoise::uncounted_share): sigma adds that share of the
    /// input's windowed high-pass power to the chosen value's noise.
    double uncounted_share = 0;
    /// Per pixel of rows from spread_begin (covering the rows chosen): the
    /// input's spreads around this frame and their numbers of terms, as
    /// spread_rows lays them out (temporal_spread.h). Null, or no input among
    /// the estimators: no per-pixel test.
    const float* spread = nullptr;
    const float* spread_terms = nullptr;
    int spread_begin = 0;
    /// Per pixel of rows from misfit_begin (covering the rows chosen): the
    /// residual's statistics over the frames around, as misfit_rows lays them
    /// out (temporal_misfit.h). Null, or no input among the estimators: no
    /// test of a lasting misfit.
    const float* misfit = nullptr;
    int misfit_begin = 0;
    double leverage = 0;
    int rebuilt_begin = 0, rebuilt_end = 0;

    /// repeating_share, noise_repeats and uncounted_share, from the shot's repeating noise.
    void count_repeating(const RepeatingNoise& noise)
    {
        repeating_share = noise.counted_share();
        noise_repeats = noise.repeats;
        uncounted_share = noise.uncounted_share();
    }
};

/// How many pixels of a frame each estimator won, and the sum of its estimated
/// squared error over them (samples), for the report.
struct ChoiceCounts {
    std::array<std::int64_t, kEstimators> pixels{};
    std::array<double, kEstimators> squared_error{};
    void add(const ChoiceCounts& other);
};

/// ChoiceFrame::noise_scale of `pixels` pixels from their noise variance s² per
/// sample (`channels` a pixel). Made once for all frames of a band: s² does not
/// change from frame to frame.
void noise_scale_rows(const float* noise_variance, std::int64_t pixels, int channels, float* scale);

/// Writes rows [row, end) of the chosen values and their sigma (laid out like
/// the frame's rows) and the Estimator taken at each pixel (one byte a pixel),
/// and returns what was chosen. `frame`'s rebuilt rows must
/// cover [row, end) ± estimator_rebuilt_reach and its input rows ± input reach
/// (clipped to the image). Deterministic: a function of those rows only.
ChoiceCounts choose_estimators(const EstimatorOptions& options, const ChoiceFrame& frame, int row, int end,
                               float* values, float* sigma, std::uint8_t* chosen);

} // namespace modestack::denoise
