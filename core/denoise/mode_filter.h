// Spatial filtering of the spatial modes ([0052], [0058]): before the rebuild, each
// coefficient image c_j (one per kept temporal mode, see core/lowrank/projection.h)
// may be smoothed in space. Every c_j carries the pixel's per-frame noise variance
// v_p (the temporal modes are unit vectors), so the higher, weaker modes are almost
// pure noise and gain most from a blur; the first mode (≈ the shot's mean, F times
// less noisy than a frame) needs little.
//
// How each mode's filter is chosen, without a reference. Mode j ≥ 2 is filtered
// with a cross-bilateral filter whose weights come only from a guide: the first
// coefficient image, lightly pre-smoothed. c_1's noise is a different temporal
// projection of noise that is white in time, so it is independent of c_j's noise:
// the filter is linear in c_j with fixed weights A and Stein's unbiased risk
// estimate is exact in expectation:
//   SURE(A) = ‖A c − c‖² + 2 Σ_p v_p A_pp − Σ_p v_p   ≈ E‖A c − s‖², s the signal.
// The first mode cannot guide itself (the weights would depend on its own noise),
// so it only gets plain Gaussians, which are linear too. The width (and whether the
// range kernel is on) that minimises SURE, summed over the whole shot, wins; width
// 0 (no filter) is always a candidate. Dropping mode j instead costs its signal
// energy ‖s_j‖² ≈ ‖c_j‖² − Σ v_p, and the noise terms cancel in the difference, so
// `auto` keeps the prefix of modes 1..N that maximises Σ_j (signal_j − SURE_j).
//
// v_p is estimated per sample from the energy the first K modes leave,
// (‖x_p‖² − Σ_{j≤K} c_j(p)²) / (F − K), pooled over a small window; it also sets
// the range kernel's scale (differences of the guide measured in its own noise).
// The SVD picks its modes for their energy, so a mode made of noise holds more of
// it than v_p (up to (1 + √(F/P))² on white noise, and about 2× on our renderer's
// heterogeneous noise, whose noisiest pixels the top noise modes gather), and the
// residual then holds less. Each mode's noise is therefore scaled to its own
// high-pass energy: scale_j = Σ_p HP(c_j)_p² / (1 + 1/n) / Σ_p v_p, HP the
// difference to the mean of the n = 4 neighbours. Smooth signal barely passes the
// high-pass; edges and texture do, which errs on the safe side (less filtering,
// fewer modes) up to the cap below: a mean that reaches it measured edges, not
// noise. On a lit mode of direct light that is the rule (the first mode sat at the
// cap on most DiffDir shots measured), and the cap itself still blurred the mode
// across its shadows' edges. Edges are a minority of the pixels, so they raise the
// mean of the per-sample ratio q = HP² / (1 + 1/n) / v_p but barely its median; a
// median alone, though, follows the quiet bulk of heterogeneous render noise (it
// read the noise modes a third low and kept 16 modes where 3 were best). So a
// mode at the cap gets median_j(q) times the mean-over-median that noise itself
// shows, the largest of the later half of the surveyed modes (the most nearly pure
// noise), between 1 and the cap (bench/results/estimators.md, section 13). Below
// the cap the mean stands: on indirect light a first mode at 2.3 whose median said
// 1.6 measured best at the mean's blur, 3.3× better than at the median's.
// Noise that repeats from frame to frame (a fixed seed) lies in the modes, not in
// the residual v_p is taken from, so a mode can hold many times v_p of noise: then
// the cap below is raised by what the measured repeating noise can put in one
// mode (survey_pass.cpp, noise_scale_cap).
// Everything is computed per image row from data within a fixed halo, and sums are
// kept per row and added in row order, so streamed and kept shots give the same bits.
#pragma once

#include "core/lowrank/band.h"
#include "core/lowrank/confidence.h"

#include <cstdint>
#include <string>
#include <vector>

namespace modestack::denoise {

/// Knobs of the mode filter.
struct ModeFilterOptions {
    bool enabled = false;
    /// Spatial Gaussian widths σ tried, in pixels (0 = no filter is always tried).
    std::vector<double> widths{0.75, 1.0, 1.5, 2.0, 3.0};
    /// Range-kernel widths ρ tried for the guided filter of modes ≥ 2: a guide difference
    /// of ρ·√channels noise deviations (of the difference) scales a weight by e^(-1/2).
    /// Plain Gaussians (no range kernel) are always tried as well.
    std::vector<double> range_scales{2.0};
    /// Feature channels per pixel (albedo, normal, depth: feature_guide.h) passed with
    /// every band; 0: no feature guide. With features, each width is also tried with a
    /// feature range kernel of each width below, alone and with the c_1 kernel.
    int feature_channels = 0;
    /// Feature range widths ρ_f tried: a normalised feature difference of ρ_f (RMS
    /// over the feature channels) scales a weight by e^(-1/2).
    std::vector<double> feature_ranges{0.25, 1.0};
    /// Modes surveyed (and the K of the noise estimate): min(this, F − 2, modes found).
    int max_modes = 16;
    /// Pre-smoothing of the guide (c_1), Gaussian σ in pixels.
    double guide_smoothing = 1.0;
    /// Pooling radius of the noise variance estimate, in pixels.
    int noise_radius = 2;
    /// SURE is evaluated on a global grid of every s-th pixel in x and y, s chosen so
    /// that at most this many pixels are visited (it is an unbiased estimate either way).
    std::int64_t survey_pixels = std::int64_t(1) << 16;
};

/// One filter: width 0 is the identity; range and feature_range 0 a plain Gaussian.
struct FilterCandidate {
    double width = 0;          ///< spatial σ, pixels
    double range = 0;          ///< c_1 range-kernel width in guide-noise units; 0 = none
    double feature_range = 0;  ///< feature range-kernel width (normalised units); 0 = none
};

/// Largest noise scale a mode gets where no noise is known to repeat. SVD
/// over-fitting raised the noise of pure-noise modes by at most ~2.05× on our
/// renders; a larger high-pass ratio is texture or edges, not noise, and must not
/// make a clean (or nearly clean) shot look noisy.
inline constexpr double kMaximumNoiseScale = 4.0;

/// What the survey found for one mode.
struct ModeFilterChoice {
    int candidate = 0;   ///< index into ModeFilterPlan::candidates
    double width = 0;    ///< chosen spatial σ (0 = not filtered)
    double range = 0;    ///< chosen range width (0 = plain Gaussian)
    double feature_range = 0;  ///< chosen feature range width (0 = not feature-guided)
    double sure = 0;     ///< SURE of the chosen filter: estimated ‖A c − s‖²
    double unfiltered_sure = 0;  ///< SURE without filtering (= Σ v_p)
    double signal = 0;   ///< estimated signal energy ‖s‖² = ‖c‖² − Σ v_p
    double noise_scale = 1;  ///< the mode's noise energy over Σ v_p (see the file comment)
    bool kept = false;   ///< part of the rebuild
};

/// The survey's outcome: a filter per mode and the number of modes.
struct ModeFilterPlan {
    std::vector<FilterCandidate> candidates;
    std::vector<ModeFilterChoice> modes;  ///< one per surveyed mode, in mode order
    int kept_modes = 0;                   ///< modes kept
    int survey_stride = 1;                ///< pixel grid step of the survey
    double guide_smoothing = 1.0;         ///< pre-smoothing of the guide, as surveyed
    int feature_channels = 0;             ///< feature channels the filter expects with each band
    std::string reasoning;                ///< one sentence for the report
};

/// The candidates tried: identity, then each width plain, then each width × range,
/// then (with features) each width × feature range, alone and with each range.
std::vector<FilterCandidate> filter_candidates(const ModeFilterOptions& options);
/// Rows the filter reads around an output row (largest kernel + guide smoothing).
int mode_filter_halo(const ModeFilterOptions& options);

/// Writes the noise variance v of every sample of a band (all its rows) into
/// `variance`: the energy left by the first K = coefficients.frames modes per
/// degree of freedom, pooled over the (2·radius+1)² window clipped to the band.
/// With `frame_scales` D (coefficients projected with D⁻¹ V, frame_weighting.h)
/// the energy is that of x_t / D_t. Needs K < noisy.frames. Throws
/// modestack::Error (internal) on mismatched shapes.
void coefficient_noise_variance(const lowrank::BandView& noisy, const lowrank::BandView& coefficients,
                                const lowrank::ImageBandShape& shape, int radius,
                                std::vector<float>& variance, const Eigen::VectorXd& frame_scales = {});

/// Accumulates SURE of every candidate and mode over the shot, band by band.
class SureSurvey {
public:
    /// For a shot of `width` × `height` pixels of `channels` channels and `modes` surveyed modes.
    SureSurvey(const ModeFilterOptions& options, int width, int height, int channels, int modes);
    /// Adds rows [valid_y0, valid_y1) of a band whose first row is image row `band_y0`:
    /// `coefficients` holds the band's `modes` coefficient images, `noise_variance` the
    /// output of coefficient_noise_variance, `features` the band's normalised feature
    /// rows ([row][x][options.feature_channels]; null without features). Each image
    /// row may be added once.
    void add_band(const lowrank::BandView& coefficients, const std::vector<float>& noise_variance,
                  const lowrank::ImageBandShape& shape, int band_y0, int valid_y0, int valid_y1,
                  const float* features = nullptr);
    /// Chooses a filter per mode and N: `fixed_rank` > 0 keeps that many modes,
    /// 0 keeps the prefix that maximises Σ (signal − SURE) (at least 1). Each
    /// mode's noise scale is at most `noise_scale_cap`.
    ModeFilterPlan finish(int fixed_modes, double noise_scale_cap = kMaximumNoiseScale) const;

    /// The sums of image rows [row_begin, row_end) as add_band left them (empty for
    /// rows not added and rows off the survey's grid), and their restoration, for a
    /// survey split over farm tasks (io/stage_files.h): finish() then gives the same
    /// plan as one survey.
    std::vector<std::vector<double>> row_sums(int row_begin, int row_end) const;
    /// Throws modestack::Error (internal) when a row's length does not match this survey.
    void restore_row_sums(int row_begin, std::vector<std::vector<double>> sums);
    /// Doubles per added image row.
    std::size_t row_sum_length() const;

private:
    ModeFilterOptions m_options;
    std::vector<FilterCandidate> m_candidates;
    int m_width, m_height, m_channels, m_modes, m_stride;
    // Per image row: [mode][candidate]{fit, trace}, [mode] energy, noise, [mode]
    // high-pass energy; added in row order by finish().
    std::vector<std::vector<double>> m_rows;
};

/// Filters rows [valid_y0, valid_y1) of the first `rank` coefficient images with the
/// plan's choices into `filtered` (valid rows × rank modes) and writes each pixel's
/// noise gain Σ_q a_pq² per mode into `gains` ([mode][valid pixel]; 1 = unfiltered):
/// the filtered mode keeps v_p·gain of the noise. `features` as for SureSurvey::add_band
/// (plan.feature_channels per pixel).
void filter_coefficients(const lowrank::BandView& coefficients, const std::vector<float>& noise_variance,
                         const lowrank::ImageBandShape& shape, int valid_y0, int valid_y1,
                         const ModeFilterPlan& plan, int kept_modes, lowrank::MutableBandView filtered,
                         std::vector<float>& gains, const float* features = nullptr);

}  // namespace modestack::denoise
