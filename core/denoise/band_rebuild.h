// Pass 2's arithmetic for one band, shared by a whole run's rebuild, a farm
// modes task and (the temporal part) a farm write task, so that all three give
// the same bits: the temporal matrices of the rebuild (RebuildBasis), and for a
// band read with its halo the coefficient images (projected, then the valid
// rows filtered and shrunk), the unfiltered rebuild of the rows sigma's windows
// read, sigma's noise level s² and the mode filter's kept-noise gains.
#pragma once

#include "core/common/scratch_buffer.h"
#include "core/denoise/engine.h"
#include "core/denoise/shot_stream.h"
#include "core/denoise/training.h"
#include "core/lowrank/basis.h"
#include "core/lowrank/confidence.h"

#include <Eigen/Dense>

#include <optional>
#include <utility>
#include <vector>

namespace modestack::denoise {

/// The temporal matrices of pass 2.
struct RebuildBasis {
    int kept_modes = 0;    ///< N
    int rebuild_modes = 0; ///< modes the outputs are rebuilt from (more than N with --rank-map)
    int projected = 0;     ///< modes projected on (the mode filter's noise estimate needs its survey's)
    int output_modes = 0;  ///< modes the outputs are rebuilt from changed coefficients (0: the unfiltered N)
    Eigen::MatrixXd temporal;             ///< F × rebuild_modes: the rebuild weights (B, smoothed)
    Eigen::MatrixXd temporal_rank;        ///< F × N of them: the unfiltered rebuild sigma's residual uses
    Eigen::MatrixXd temporal_projected;   ///< F × projected: the projection (A)
    Eigen::VectorXd leverages;            ///< h_t for sigma
    /// D, the frame scales the modes were fitted with (frame_weighting.h; empty: even):
    /// B = D V and A = D⁻¹ V, and frame t's noise is D_t² times the whitened s².
    Eigen::VectorXd frame_scales;
    std::vector<double> shrinkage;        ///< --shrink optimal: η(σ_j)/σ_j per kept mode (empty: none)
    WeightSmoothingPlan weight_smoothing; ///< what --weight-smoothing did per kept mode
};

/// The matrices for N = `rank` modes of `basis`; `surveyed` modes the mode filter
/// surveyed (0 without it), `training` the --train-frames sums (null: none),
/// `noise_sigma` the rank rule's noise level (for --shrink optimal), `frame_scales`
/// the D the basis was fitted with (empty: even).
RebuildBasis make_rebuild_basis(const Settings& settings, const lowrank::Basis& basis, int kept_modes,
                                int surveyed, const TrainingGram* training, double noise_sigma,
                                const Eigen::VectorXd& frame_scales = {});

/// Frame t's noise level over the shot's that the estimator choice scales s by:
/// the frame scale D_t the modes were fitted with (s is then the whitened
/// noise), else the frame's factor of the input as read (frame_noise.h).
double frame_noise_factor(const RebuildBasis& modes, const std::vector<double>& factors, int t);

/// The mode filter's feature rows over `data`'s rows (with its halo) in
/// `features`, or null when no feature guides it (`filter.feature_channels` 0).
const float* band_features(const ModeFilterOptions& filter, const FeatureGuide* guide, const Band& data,
                           std::vector<float>& features);

/// What kept_noise_of_frame counts. The SVD gathers more than its share of
/// noise into its noise modes, and a mode whose frames are noisier than the
/// shot's mean (a light on in a few frames) holds more still; the mode filter
/// measures that as each mode's noise scale (mode_filter.h). Sigma counts it.
/// The choice's SURE needs the rebuild's derivative at the sample, which the
/// noise a mode holds does not change: it takes the gains alone.
/// With frame scales D (B = D V, frame_weighting.h) the derivative's B_tj A_tj
/// is V_tj² = (B_tj / D_t)² (smoothed B: its stand-in, as without D), and the
/// noise kept is B_tj² times the whitened noise: D_t² in it.
enum class KeptNoise {
    Gain,  ///< Σ_j (B_tj / D_t)² · gain_j(p): SURE's stand-in for the rebuild's derivative
    Noise, ///< Σ_j B_tj² · gain_j(p) · noise_scale_j: the noise kept, over the whitened s², for sigma
};

/// Pass 2 up to the frames for one band at a time; its buffers are reused from
/// band to band (fresh pages would cost the kernel's zeroing every band).
class BandRebuilder {
public:
    /// `plan` the mode filter's choices (empty without it), `features` its guide (null: none).
    BandRebuilder(const Settings& settings, const ShotShape& shape, const RebuildBasis& modes,
                  const ModeFilterOptions& filter_options, const ModeFilterPlan& plan, int surveyed,
                  const FeatureGuide* features);

    /// For rows [row, end) of `data` (a band with its halo): the coefficients
    /// (valid rows filtered and shrunk, halo rows as projected), the unfiltered
    /// rebuild of the rows sigma's windows read (rebuilt()), s² and the kept-noise
    /// gains of the valid rows. `residual` (optional; valid rows × N modes)
    /// receives the valid rows' unfiltered coefficient images before the filter
    /// changes them; `ranks` (optional, --rank-map) each valid pixel's rank;
    /// `means` (optional; frame t's valid rows at means + t · means_stride) each
    /// frame's windowed residual mean for sigma. `means` may be the valid rows
    /// of `data` itself (a streamed band): nothing reads them afterwards.
    void prepare(const Band& data, int row, int end, const lowrank::MutableBandView* residual,
                 std::vector<float>* ranks, float* means = nullptr, std::int64_t means_stride = 0);

    /// The image rows [begin, end) of `data` that sigma's windows read for rows [row, end).
    std::pair<int, int> sigma_rows(const Band& data, int row, int end) const;
    /// What each rebuilt sample of frame t keeps of the noise under the mode
    /// filter, for `samples` samples of the gains' pixels: KeptNoise::Gain
    /// h_t(p) = Σ_j V_tj² · gain_j(p), in units of the pixel's noise as if every
    /// mode held its share; KeptNoise::Noise weighs each mode by its measured
    /// noise scale (ModeFilterChoice::noise_scale; 1 past the survey's modes).
    void kept_noise_of_frame(const Eigen::MatrixXd& temporal, int t, int modes, const float* gains,
                             std::int64_t samples, float* kept, KeptNoise what) const;

    const lowrank::ConfidenceOptions& confidence() const { return m_confidence; }
    /// [mode][sample] of the last band with its halo.
    ScratchBuffer<float>& coefficients() { return m_coefficients; }
    /// [frame][sample] of sigma_rows(): the unfiltered rebuild, then (the caller's) output rows.
    ScratchBuffer<float>& rebuilt() { return m_rebuilt; }
    /// Sigma's s² of the last band's valid rows.
    const std::vector<float>& noise_variance() const { return m_noise_variance; }
    /// The mode filter's kept-noise gain per valid pixel and mode of the last band.
    const std::vector<float>& gains() const { return m_gains; }
    /// The first mode's filter bias per valid sample of the last band
    /// (first_mode_filter_bias; empty without the mode filter).
    const std::vector<float>& first_mode_bias() const { return m_first_mode_bias; }

private:
    void filter(const Band& data, int row, int end, std::vector<float>* ranks);

    const Settings& m_settings;
    ShotShape m_shape;
    const RebuildBasis& m_modes;
    const ModeFilterOptions& m_filter_options;
    const ModeFilterPlan& m_plan;
    int m_surveyed;
    const FeatureGuide* m_features;
    lowrank::ConfidenceOptions m_confidence;
    std::vector<float> m_filtered;         // the filter's output
    ScratchBuffer<float> m_coefficients;   // [mode][sample] of the band with its halo
    ScratchBuffer<float> m_rebuilt;        // [frame][sample] of sigma_rows()
    std::vector<float> m_noise_variance;   // sigma's s² of the valid rows
    std::vector<float> m_gains;            // kept-noise gain per valid pixel and mode
    std::vector<float> m_first_unfiltered; // the first mode's valid rows before the filter
    std::vector<float> m_first_mode_bias;  // first_mode_filter_bias of the valid rows
};

/// Sigma's term for the mode filter's bias of the first mode, per sample
/// (docs/design.md, "Sigma"). The first mode's coefficients are a weighted sum
/// over every frame: its filter's bias d = filtered − unfiltered is measured
/// with a frame's noise s²·(1 − gain), while a frame's rebuild carries it times
/// B_t1² (about 1/F; first_mode_term). That is a hard shadow's edge in the
/// shot's mean light, which the first mode's plain Gaussian blurs and which no
/// other term of sigma sees. b² is the posterior mean given d under a prior
/// learnt per image row (lowrank/bias_prior.h), with the row's empirical null;
/// an unfiltered value outside its row neighbours' range is first cut to it (a
/// firefly left in the mode is not a bias of the filter). `samples` are whole
/// image rows of `width` × `channels`; `gains` the first mode's, one per pixel.
/// Throws modestack::Error (internal) on a partial row.
void first_mode_filter_bias(const float* filtered, const float* unfiltered, const float* noise_variance,
                            const float* gains, std::int64_t samples, int width, int channels, float* bias);
/// Sigma's term of frame t for that bias: `bias` (first_mode_filter_bias's
/// output; empty: no term) times B_t1², the first mode's rebuild weight squared.
lowrank::SigmaExtraTerm first_mode_term(const Eigen::MatrixXd& temporal, int t,
                                        const std::vector<float>& bias);

} // namespace modestack::denoise
