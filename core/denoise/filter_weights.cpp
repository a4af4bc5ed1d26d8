#include "core/denoise/filter_weights.h"

#include "core/denoise/mode_filter.h"

#include <tbb/parallel_for.h>

#include <algorithm>

namespace modestack::denoise {

using lowrank::BandView;
using lowrank::ImageBandShape;

std::vector<double> gaussian_1d(double width)
{
    int radius = kernel_radius(width);
    std::vector<double> kernel(2 * radius + 1);
    double sum = 0;
    for (int d = -radius; d <= radius; ++d)
        sum += kernel[d + radius] = std::exp(-0.5 * d * d / (width * width));
    for (double& value : kernel)
        value /= sum;
    return kernel;
}

void clipped_tap_sums(const std::vector<double>& taps, int radius, int at, int length, double& sum, double& squares)
{
    sum = squares = 0;
    for (int q = std::max(0, at - radius); q <= std::min(length - 1, at + radius); ++q)
        sum += taps[q - at + radius], squares += taps[q - at + radius] * taps[q - at + radius];
}

void smooth_clipped(const float* image, const ImageBandShape& shape, double width, int y0, int y1,
                    const std::function<void(int, const double*)>& row_done)
{
    const std::vector<double> taps = gaussian_1d(width);
    const int radius = kernel_radius(width);
    const std::int64_t row_length = static_cast<std::int64_t>(shape.width) * shape.channels;
    const int first_row = std::max(0, y0 - radius), last_row = std::min(shape.height - 1, y1 - 1 + radius);
    const auto clipped_weight = [&](int at, int length) {
        double sum = 0, squares = 0;
        clipped_tap_sums(taps, radius, at, length, sum, squares);
        return sum;
    };
    std::vector<double> horizontal(static_cast<std::size_t>(last_row - first_row + 1) * row_length);
    tbb::parallel_for(first_row, last_row + 1, [&](int y) {
        const float* row = image + y * row_length;
        double* target = horizontal.data() + (y - first_row) * row_length;
        for (int x = 0; x < shape.width; ++x)
            for (int c = 0; c < shape.channels; ++c) {
                double sum = 0;
                for (int q = std::max(0, x - radius); q <= std::min(shape.width - 1, x + radius); ++q)
                    sum += taps[q - x + radius] * row[q * shape.channels + c];
                target[x * shape.channels + c] = sum;
            }
    });
    std::vector<double> column_weight(static_cast<std::size_t>(shape.width));
    for (int x = 0; x < shape.width; ++x)
        column_weight[static_cast<std::size_t>(x)] = clipped_weight(x, shape.width);
    tbb::parallel_for(y0, y1, [&](int y) {
        const double row_weight = clipped_weight(y, shape.height);
        std::vector<double> sum(static_cast<std::size_t>(row_length), 0.0);
        for (int q = std::max(0, y - radius); q <= std::min(shape.height - 1, y + radius); ++q) {
            const double tap = taps[q - y + radius];
            const double* source = horizontal.data() + (q - first_row) * row_length;
            for (std::int64_t k = 0; k < row_length; ++k)
                sum[static_cast<std::size_t>(k)] += tap * source[k];
        }
        for (int x = 0; x < shape.width; ++x) {
            const double total = column_weight[static_cast<std::size_t>(x)] * row_weight;
            for (int c = 0; c < shape.channels; ++c)
                sum[static_cast<std::size_t>(x * shape.channels + c)] /= total;
        }
        row_done(y, static_cast<const double*>(sum.data()));
    });
}

std::vector<float> spatial_weights(double width)
{
    const int radius = kernel_radius(width);
    std::vector<float> table(static_cast<std::size_t>(2 * radius * radius + 1));
    for (std::size_t d2 = 0; d2 < table.size(); ++d2)
        table[d2] = static_cast<float>(std::exp(-0.5 / (width * width) * static_cast<double>(d2)));
    return table;
}

Guide build_guide(const BandView& coefficients, const std::vector<float>& noise_variance, const ImageBandShape& shape,
                  double smoothing, const float* features, int feature_channels)
{
    Guide guide;
    guide.width = shape.width, guide.height = shape.height, guide.channels = shape.channels;
    const std::int64_t plane = guide.plane();
    guide.value.resize(static_cast<std::size_t>(plane * shape.channels));
    guide.noise.resize(guide.value.size());
    // White noise through a normalised kernel k keeps Σ k² of its variance per
    // dimension (in the interior).
    double gain_1d = 1;
    if (smoothing > 0) {
        gain_1d = 0;
        for (double value : gaussian_1d(smoothing))
            gain_1d += value * value;
    }
    const auto place_row = [&](int y, const double* row) {
        const std::int64_t first = y * static_cast<std::int64_t>(shape.width);
        for (int x = 0; x < shape.width; ++x)
            for (int c = 0; c < shape.channels; ++c) {
                const std::int64_t sample = (first + x) * shape.channels + c;
                guide.value[static_cast<std::size_t>(c * plane + first + x)] = static_cast<float>(row[x * shape.channels + c]);
                guide.noise[static_cast<std::size_t>(c * plane + first + x)] =
                    static_cast<float>(noise_variance[static_cast<std::size_t>(sample)] * gain_1d * gain_1d);
            }
    };
    if (smoothing > 0) {
        smooth_clipped(coefficients.data, shape, smoothing, 0, shape.height, place_row);
    } else {
        const std::int64_t row_length = static_cast<std::int64_t>(shape.width) * shape.channels;
        std::vector<double> row(static_cast<std::size_t>(row_length));
        for (int y = 0; y < shape.height; ++y) {
            std::copy(coefficients.data + y * row_length, coefficients.data + (y + 1) * row_length, row.begin());
            place_row(y, row.data());
        }
    }
    if (features && feature_channels > 0) {
        guide.feature_channels = feature_channels;
        guide.features.resize(static_cast<std::size_t>(plane * feature_channels));
        for (std::int64_t p = 0; p < plane; ++p)
            for (int k = 0; k < feature_channels; ++k)
                guide.features[static_cast<std::size_t>(k * plane + p)] = features[p * feature_channels + k];
    }
    return guide;
}

ExponentScales exponent_scales(const FilterCandidate& candidate, const Guide& guide)
{
    ExponentScales scales;
    if (candidate.range > 0)
        scales.range = static_cast<float>(-0.5 / (candidate.range * candidate.range * guide.channels));
    if (candidate.feature_range > 0 && guide.feature_channels > 0)
        scales.feature =
            static_cast<float>(-0.5 / (candidate.feature_range * candidate.feature_range * guide.feature_channels));
    return scales;
}

void WeightWindow::centre(int x, int y)
{
    m_x = x, m_y = y;
    m_wide_x0 = std::max(0, x - m_widest), m_wide_x1 = std::min(m_guide.width - 1, x + m_widest);
    m_wide_y0 = std::max(0, y - m_widest), m_wide_y1 = std::min(m_guide.height - 1, y + m_widest);
    m_have_distances = false;
    for (Factor& factor : m_factors)
        factor.current = false;
}

const std::vector<float>& WeightWindow::spatial(double width)
{
    for (const auto& [table_width, table] : m_spatial_tables)
        if (table_width == width)
            return table;
    m_spatial_tables.emplace_back(width, spatial_weights(width));
    return m_spatial_tables.back().second;
}

const std::vector<float>& WeightWindow::guided_factor(ExponentScales scales)
{
    const int wide_width = m_wide_x1 - m_wide_x0 + 1;
    const std::size_t taps = static_cast<std::size_t>(wide_width) * (m_wide_y1 - m_wide_y0 + 1);
    if (!m_have_distances) {
        m_range_distance.assign(taps, 0.0f);
        m_feature_distance.assign(taps, 0.0f);
        const std::int64_t centre = static_cast<std::int64_t>(m_y) * m_guide.width + m_x;
        std::size_t index = 0;
        for (int qy = m_wide_y0; qy <= m_wide_y1; ++qy)
            for (int qx = m_wide_x0; qx <= m_wide_x1; ++qx, ++index) {
                const std::int64_t other = static_cast<std::int64_t>(qy) * m_guide.width + qx;
                float range = 0;
                for (int c = 0; c < m_guide.channels; ++c) {
                    const float* value = m_guide.value_plane(c);
                    const float* noise = m_guide.noise_plane(c);
                    range += range_term(value[centre], value[other], noise[centre], noise[other]);
                }
                float feature = 0;
                for (int k = 0; k < m_guide.feature_channels; ++k) {
                    const float* plane = m_guide.feature_plane(k);
                    feature += feature_term(plane[centre], plane[other]);
                }
                m_range_distance[index] = range, m_feature_distance[index] = feature;
            }
        m_have_distances = true;
    }
    Factor* factor = nullptr;
    for (Factor& candidate : m_factors)
        if (candidate.scales.range == scales.range && candidate.scales.feature == scales.feature)
            factor = &candidate;
    if (!factor)
        factor = &m_factors.emplace_back(Factor{scales, {}, false});
    if (!factor->current) {
        factor->values.resize(taps);
        for (std::size_t i = 0; i < taps; ++i) {
            const float range = scales.range != 0 ? m_range_distance[i] : 0.0f;
            const float feature = scales.feature != 0 ? m_feature_distance[i] : 0.0f;
            factor->values[i] = weight_exp(guided_exponent(scales, range, feature));
        }
        factor->current = true;
    }
    return factor->values;
}

double WeightWindow::compute(const FilterCandidate& candidate)
{
    const int radius = kernel_radius(candidate.width);
    x0 = std::max(0, m_x - radius), x1 = std::min(m_guide.width - 1, m_x + radius);
    y0 = std::max(0, m_y - radius), y1 = std::min(m_guide.height - 1, m_y + radius);
    weights.resize(static_cast<std::size_t>(x1 - x0 + 1) * (y1 - y0 + 1));
    const std::vector<float>& spatial_table = spatial(candidate.width);
    const ExponentScales scales = exponent_scales(candidate, m_guide);
    const bool guided = scales.range != 0 || scales.feature != 0;
    const float* factor = guided ? guided_factor(scales).data() : nullptr;
    const int wide_width = m_wide_x1 - m_wide_x0 + 1;
    double sum = 0;
    std::size_t index = 0;
    for (int qy = y0; qy <= y1; ++qy)
        for (int qx = x0; qx <= x1; ++qx, ++index) {
            const int distance2 = (qx - m_x) * (qx - m_x) + (qy - m_y) * (qy - m_y);
            float weight = spatial_table[static_cast<std::size_t>(distance2)];
            if (guided)
                weight *= factor[static_cast<std::size_t>(qy - m_wide_y0) * wide_width + (qx - m_wide_x0)];
            sum += weights[index] = weight;
        }
    self = static_cast<std::size_t>(m_y - y0) * (x1 - x0 + 1) + (m_x - x0);
    return sum;
}

void WeightWindow::apply(const float* pixels, int first_row, int per_pixel, float* sums) const
{
    std::fill(sums, sums + per_pixel, 0.0f);
    std::size_t index = 0;
    for (int qy = y0; qy <= y1; ++qy)
        for (int qx = x0; qx <= x1; ++qx, ++index) {
            const float weight = weights[index];
            const float* values = pixels + (static_cast<std::int64_t>(qy - first_row) * m_guide.width + qx) * per_pixel;
            for (int i = 0; i < per_pixel; ++i)
                sums[i] += weight * values[i];
        }
}

}  // namespace modestack::denoise
