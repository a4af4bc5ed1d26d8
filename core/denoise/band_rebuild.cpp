#include "core/denoise/band_rebuild.h"

#include "core/common/error.h"
#include "core/denoise/frame_weighting.h"
#include "core/lowrank/bias_prior.h"
#include "core/lowrank/projection.h"
#include "core/lowrank/shrinkage.h"

#include <algorithm>

namespace modestack::denoise {

namespace {
// The median of χ² with one degree of freedom.
constexpr double kChiSquareOneMedian = 0.45493642311957283;
} // namespace

RebuildBasis make_rebuild_basis(const Settings& settings, const lowrank::Basis& basis, int kept_modes,
                                int surveyed, const TrainingGram* training, double noise_sigma,
                                const Eigen::VectorXd& frame_scales)
{
    if (training && frame_scales.size() > 0)
        throw internal_error(
            "make_rebuild_basis: training frames fit modes of their own, without frame scales");
    RebuildBasis result;
    result.kept_modes = kept_modes;
    // --rank-map: pixels may use modes beyond N, up to those the filter surveyed.
    result.rebuild_modes =
        settings.rank_map.enabled
            ? std::max(kept_modes, std::min(kept_modes + settings.rank_map.extra_modes, surveyed))
            : kept_modes;
    // With training frames the projection (A) and the rebuild (B) differ:
    // training.h. Modes fitted to X D⁻¹ are projected with D⁻¹ V and rebuilt
    // with D V (frame_weighting.h).
    result.frame_scales = frame_scales;
    result.temporal = training ? training->weights(basis, kept_modes)
                               : rebuild_weights(basis.temporal.leftCols(result.rebuild_modes), frame_scales);
    // --weight-smoothing: B smoothed, A kept. B as it rebuilds the frames, D in
    // it: smoothing D⁻¹-weighted modes and scaling back would put the noise of
    // the measured D_t into every frame's rebuild as flicker.
    const bool smooth = settings.weight_smoothing.enabled;
    if (smooth)
        result.temporal =
            smooth_temporal_weights(result.temporal, settings.weight_smoothing, result.weight_smoothing);
    result.temporal_rank = result.temporal.leftCols(kept_modes);
    const auto projection = [&](int modes) -> Eigen::MatrixXd {
        return training ? training->projector(basis, modes)
                        : projection_weights(basis.temporal.leftCols(modes), frame_scales);
    };
    result.leverages = training || smooth || frame_scales.size() > 0
                           ? training_leverages(projection(kept_modes), result.temporal_rank)
                           : lowrank::leverages(basis, kept_modes);
    if (settings.optimal_shrinkage)
        result.shrinkage = lowrank::optimal_shrinkage_factors(basis, noise_sigma, kept_modes);
    result.projected = settings.mode_filter.enabled ? std::max(result.rebuild_modes, surveyed) : kept_modes;
    result.temporal_projected = projection(result.projected);
    result.output_modes = settings.mode_filter.enabled ? result.rebuild_modes
                          : settings.optimal_shrinkage ? kept_modes
                                                       : 0;
    return result;
}

double frame_noise_factor(const RebuildBasis& modes, const std::vector<double>& factors, int t)
{
    return modes.frame_scales.size() > 0 ? modes.frame_scales[t] : factors.at(static_cast<size_t>(t));
}

BandRebuilder::BandRebuilder(const Settings& settings, const ShotShape& shape, const RebuildBasis& modes,
                             const ModeFilterOptions& filter_options, const ModeFilterPlan& plan,
                             int surveyed, const FeatureGuide* features)
    : m_settings(settings), m_shape(shape), m_modes(modes), m_filter_options(filter_options), m_plan(plan),
      m_surveyed(surveyed), m_features(features)
{
    m_confidence.radius = settings.sigma_radius;
}

std::pair<int, int> BandRebuilder::sigma_rows(const Band& data, int row, int end) const
{
    // Sigma's window reads radius + 1 rows around a pixel (see confidence.h).
    const int halo = m_settings.sigma_radius + 1;
    return {std::max(data.row_begin, row - halo), std::min(data.row_end, end + halo)};
}

const float* band_features(const ModeFilterOptions& filter, const FeatureGuide* guide, const Band& data,
                           std::vector<float>& features)
{
    if (filter.feature_channels == 0)
        return nullptr;
    guide->read_rows(data.row_begin, data.row_end, features);
    return features.data();
}

void BandRebuilder::prepare(const Band& data, int row, int end, const lowrank::MutableBandView* residual,
                            std::vector<float>* ranks, float* means, std::int64_t means_stride)
{
    const int frames = m_shape.frames;
    const std::int64_t row_samples = static_cast<std::int64_t>(m_shape.width) * m_shape.channels;
    const std::int64_t offset = (row - data.row_begin) * row_samples, valid = (end - row) * row_samples;
    lowrank::BandView noisy = data.view(frames).view();
    m_coefficients.resize(static_cast<size_t>(data.rows) * m_modes.projected); // every value written below
    lowrank::MutableBandView coefficient_view{m_coefficients.data(), data.rows, m_modes.projected, data.rows};
    lowrank::project_coefficients(noisy, m_modes.temporal_projected, coefficient_view);
    if (residual) {
        for (int j = 0; j < m_modes.kept_modes; ++j)
            std::copy_n(m_coefficients.begin() + j * data.rows + offset, valid,
                        residual->data + j * residual->frame_stride);
    }
    // Only the rows sigma's windows read are rebuilt unfiltered (the mode
    // filter's wider halo needs coefficients only).
    const auto [residual_begin, residual_end] = sigma_rows(data, row, end);
    const std::int64_t residual_first = (residual_begin - data.row_begin) * row_samples;
    const std::int64_t rebuilt_stride = (residual_end - residual_begin) * row_samples;
    m_rebuilt.resize(static_cast<size_t>(rebuilt_stride) * frames);
    lowrank::rebuild_from_coefficients(
        {m_coefficients.data() + residual_first, rebuilt_stride, m_modes.kept_modes, data.rows},
        m_modes.temporal_rank, {m_rebuilt.data(), rebuilt_stride, frames, rebuilt_stride});
    // The filter reads the noisy band, which the means may overwrite: it goes first.
    // The first mode's filter bias (below) needs its values before the filter.
    const bool first_mode_filtered = m_settings.mode_filter.enabled && m_modes.rebuild_modes > 0;
    if (first_mode_filtered)
        m_first_unfiltered.assign(m_coefficients.begin() + offset, m_coefficients.begin() + offset + valid);
    if (m_settings.mode_filter.enabled)
        filter(data, row, end, ranks);
    lowrank::ImageBandShape shape{m_shape.width, residual_end - residual_begin, m_shape.channels};
    m_noise_variance.resize(static_cast<size_t>(valid));
    lowrank::residual_noise_variance(
        {noisy.data + residual_first, rebuilt_stride, frames, noisy.frame_stride},
        {m_rebuilt.data(), rebuilt_stride, frames, rebuilt_stride}, shape, m_modes.kept_modes,
        row - residual_begin, end - residual_begin, m_confidence, m_noise_variance.data(), means,
        means_stride, m_modes.frame_scales);
    for (size_t j = 0; j < m_modes.shrinkage.size(); ++j) // --shrink optimal, the band's own rows
        for (std::int64_t i = 0; i < valid; ++i)
            m_coefficients[j * data.rows + offset + i] *= static_cast<float>(m_modes.shrinkage[j]);
    // From the coefficients as the output is rebuilt from them (filtered, shrunk), as a farm's write task
    // does.
    m_first_mode_bias.clear();
    if (first_mode_filtered) {
        m_first_mode_bias.resize(static_cast<size_t>(valid));
        first_mode_filter_bias(m_coefficients.data() + offset, m_first_unfiltered.data(),
                               m_noise_variance.data(), m_gains.data(), valid, m_shape.width,
                               m_shape.channels, m_first_mode_bias.data());
    }
}

// The mode filter's part of pass 2 for rows [row, end) of `data`: filters the
// first rebuild_modes coefficient images in place (valid rows only) and leaves
// in m_gains the noise each filtered mode keeps per valid pixel (gain_j(p)), from
// which sigma's kept noise per frame follows (kept_noise_of_frame).
// With --rank-map, `ranks` receives each valid pixel's rank and every filtered
// mode is scaled by its blend weight at the pixel (rank_map.h).
void BandRebuilder::filter(const Band& data, int row, int end, std::vector<float>* ranks)
{
    const int modes = m_modes.rebuild_modes;
    const std::int64_t row_samples = static_cast<std::int64_t>(m_shape.width) * m_shape.channels;
    const std::int64_t offset = (row - data.row_begin) * row_samples, valid = (end - row) * row_samples;
    lowrank::BandView noisy = data.view(m_shape.frames).view();
    lowrank::BandView surveyed{m_coefficients.data(), data.rows, m_surveyed, data.rows};
    lowrank::ImageBandShape shape{m_shape.width, data.row_end - data.row_begin, m_shape.channels};
    std::vector<float>& filtered = m_filtered; // filter_coefficients writes every value
    filtered.resize(static_cast<size_t>(valid) * modes);
    std::vector<float> noise_variance, features;
    coefficient_noise_variance(noisy, surveyed, shape, m_settings.mode_filter.noise_radius, noise_variance,
                               m_modes.frame_scales);
    filter_coefficients(surveyed, noise_variance, shape, row - data.row_begin, end - data.row_begin, m_plan,
                        modes, {filtered.data(), valid, modes, valid}, m_gains,
                        band_features(m_filter_options, m_features, data, features));
    const std::int64_t valid_pixels = valid / m_shape.channels;
    if (ranks) {
        std::vector<float> weights;
        local_rank(surveyed, noise_variance, shape, row - data.row_begin, end - data.row_begin, m_plan,
                   m_modes.kept_modes, modes, m_gains, m_settings.rank_map.radius, weights, *ranks);
        for (int j = 0; j < modes; ++j)
            for (std::int64_t i = 0; i < valid; ++i) {
                const float weight = weights[static_cast<size_t>(j * valid_pixels + i / m_shape.channels)];
                filtered[static_cast<size_t>(j * valid + i)] *= weight;
                if (i % m_shape.channels == 0) // the kept noise of a scaled mode: w² · gain
                    m_gains[static_cast<size_t>(j * valid_pixels + i / m_shape.channels)] *= weight * weight;
            }
    }
    for (int j = 0; j < modes; ++j)
        std::copy(filtered.begin() + j * valid, filtered.begin() + (j + 1) * valid,
                  m_coefficients.begin() + j * data.rows + offset);
}

void BandRebuilder::kept_noise_of_frame(const Eigen::MatrixXd& temporal, int t, int modes, const float* gains,
                                        std::int64_t samples, float* kept, KeptNoise what) const
{
    const std::int64_t pixels = samples / m_shape.channels;
    // Per mode, V_tj² times what it holds of the noise.
    thread_local std::vector<double> weights;
    weights.resize(static_cast<size_t>(modes));
    // The gains stand for the derivative Σ_j B_tj A_tj gain_j, and B_tj A_tj =
    // V_tj² whatever the frame scale D_t; the noise kept is B_tj² gain_j times
    // the whitened coefficients' noise, D_t² in it.
    const double scale =
        what == KeptNoise::Gain ? lowrank::frame_noise_variance(m_modes.frame_scales, t) : 1.0;
    for (int j = 0; j < modes; ++j) {
        const bool surveyed = what == KeptNoise::Noise && j < static_cast<int>(m_plan.modes.size());
        weights[static_cast<size_t>(j)] = temporal(t, j) * temporal(t, j) / scale *
                                          (surveyed ? m_plan.modes[static_cast<size_t>(j)].noise_scale : 1.0);
    }
    for (std::int64_t pixel = 0; pixel < pixels; ++pixel) {
        double sum = 0;
        for (int j = 0; j < modes; ++j)
            sum += weights[static_cast<size_t>(j)] * gains[static_cast<size_t>(j * pixels + pixel)];
        std::fill_n(kept + pixel * m_shape.channels, m_shape.channels, static_cast<float>(sum));
    }
}

void first_mode_filter_bias(const float* filtered, const float* unfiltered, const float* noise_variance,
                            const float* gains, std::int64_t samples, int width, int channels, float* bias)
{
    const std::int64_t row_samples = static_cast<std::int64_t>(width) * channels;
    if (row_samples <= 0 || samples % row_samples != 0)
        throw Error(ErrorKind::Internal, "first_mode_filter_bias: samples are not whole image rows");
    std::vector<double> difference(static_cast<size_t>(row_samples)), noise(difference.size());
    lowrank::BiasRatioCounts counts{};
    auto count = [&] {
        counts.fill(0);
        for (size_t k = 0; k < difference.size(); ++k)
            ++counts[static_cast<size_t>(lowrank::bias_bin(difference[k] * difference[k] / noise[k]))];
    };
    for (std::int64_t begin = 0; begin < samples; begin += row_samples) {
        for (std::int64_t k = 0; k < row_samples; ++k) {
            const std::int64_t i = begin + k;
            // A value outside its two row neighbours' range is cut to it: the
            // first mode still holds some fireflies (an average over F frames
            // of cleaned samples), which the filter rightly removes and which
            // would read as its bias; an edge lies between its neighbours.
            double value = unfiltered[i];
            if (k >= channels && k + channels < row_samples) {
                const double left = unfiltered[i - channels], right = unfiltered[i + channels];
                value = std::clamp(value, std::min(left, right), std::max(left, right));
            }
            difference[static_cast<size_t>(k)] = static_cast<double>(filtered[i]) - value;
            // Its noise: s²·(1 − 2·a_pp + Σa²), with the gain Σa² standing in
            // for the centre weight a_pp as in the choice's SURE.
            noise[static_cast<size_t>(k)] =
                std::max(static_cast<double>(noise_variance[i]) * (1.0 - gains[i / channels]), 0.0);
        }
        count();
        // The empirical null (Efron): most of a row is unbiased, so the median of
        // t² is the noise's, 0.4549 under a Gaussian. Where it is wider (s² is a
        // high-pass estimate, and a renderer's pixel filter correlates
        // neighbours) the noise is scaled up to it, never down.
        const double null_scale = lowrank::bias_ratio_median(counts) / kChiSquareOneMedian;
        if (null_scale > 1) {
            for (double& value : noise)
                value *= null_scale;
            count();
        }
        // The bias b² as the posterior mean under the row's prior, as for
        // sigma's bias term: about 0 where noise explains the difference, about
        // its square where it cannot.
        const lowrank::BiasPosterior posterior = lowrank::fit_bias_posterior(counts);
        for (std::int64_t k = 0; k < row_samples; ++k) {
            const double d = difference[static_cast<size_t>(k)], null = noise[static_cast<size_t>(k)];
            const auto bin = static_cast<size_t>(lowrank::bias_bin(d * d / null));
            bias[begin + k] = static_cast<float>(posterior.slope[bin] * d * d + posterior.offset[bin] * null);
        }
    }
}

lowrank::SigmaExtraTerm first_mode_term(const Eigen::MatrixXd& temporal, int t,
                                        const std::vector<float>& bias)
{
    if (bias.empty())
        return {};
    return {bias.data(), temporal(t, 0) * temporal(t, 0)};
}

} // namespace modestack::denoise
