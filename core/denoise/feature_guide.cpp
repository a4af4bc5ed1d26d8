#include "core/denoise/feature_guide.h"

#include "core/common/error.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace modestack::denoise {
namespace {

// Rows read at a time while measuring the scales.
constexpr int kScaleBandRows = 64;

// Depth as guided: its logarithm, with no depth (0, negative, infinite: a miss)
// put far behind everything.
float guided_depth(float depth)
{
    if (!(depth > 1e-6f) || !std::isfinite(depth) || depth > 1e6f)
        return std::log(1e6f);
    return std::log(depth);
}

std::vector<int> spread_frames(int frames, int wanted)
{
    wanted = std::max(1, std::min(wanted, frames));
    std::vector<int> chosen;
    for (int k = 0; k < wanted; ++k)
        chosen.push_back(wanted == 1 ? 0 : static_cast<int>(static_cast<long long>(k) * (frames - 1) / (wanted - 1)));
    chosen.erase(std::unique(chosen.begin(), chosen.end()), chosen.end());
    return chosen;
}

}  // namespace

std::string auxiliary_name(Auxiliary kind)
{
    switch (kind) {
    case Auxiliary::Albedo: return "albedo";
    case Auxiliary::Normal: return "normal";
    case Auxiliary::Depth: return "depth";
    default: return "variance";
    }
}

FeatureGuide::FeatureGuide(FrameSource& source, const FeatureGuideOptions& options, Progress& progress)
    : m_source(source), m_shape(source.shape())
{
    m_frames = spread_frames(m_shape.frames, options.frames);
    std::vector<Feature> present;
    for (Auxiliary kind : options.kinds)
        if (int channels = source.auxiliary_channels(kind); channels > 0 && kind != Auxiliary::Variance)
            present.push_back({kind, channels, 1.0});
    if (present.empty())
        return;
    // Σ of squared neighbour differences per image row and feature, added in row order.
    std::vector<std::vector<double>> row_sums(static_cast<size_t>(m_shape.height),
                                              std::vector<double>(present.size(), 0.0));
    progress.begin("mode filter: measuring the feature guides", m_shape.height);
    std::vector<float> values;
    for (int row = 0; row < m_shape.height; row += kScaleBandRows) {
        throw_if_cancelled();
        const int end = std::min(m_shape.height, row + kScaleBandRows);
        const int read_end = std::min(m_shape.height, end + 1);  // the next row: vertical differences
        for (size_t f = 0; f < present.size(); ++f) {
            read_feature(present[f], row, read_end, values);
            const int channels = present[f].channels;
            const std::int64_t row_length = static_cast<std::int64_t>(m_shape.width) * channels;
            tbb::parallel_for(row, end, [&](int y) {
                const float* here = values.data() + (y - row) * row_length;
                double sum = 0;
                for (std::int64_t i = channels; i < row_length; ++i)
                    sum += static_cast<double>(here[i] - here[i - channels]) * (here[i] - here[i - channels]);
                if (y + 1 < read_end)
                    for (std::int64_t i = 0; i < row_length; ++i)
                        sum += static_cast<double>(here[i + row_length] - here[i]) * (here[i + row_length] - here[i]);
                row_sums[static_cast<size_t>(y)][f] = sum;
            });
        }
        progress.advance(end - row);
    }
    progress.end();
    const double pairs = static_cast<double>(m_shape.width - 1) * m_shape.height +
                         static_cast<double>(m_shape.width) * (m_shape.height - 1);
    for (size_t f = 0; f < present.size(); ++f) {
        double total = 0;
        for (const std::vector<double>& sums : row_sums)
            total += sums[f];
        const double scale = pairs > 0 ? std::sqrt(total / (pairs * present[f].channels)) : 0.0;
        if (!(scale > 0) || !std::isfinite(scale))
            continue;  // the same everywhere: no edge to keep
        present[f].scale = scale;
        m_features.push_back(present[f]);
        m_channels += present[f].channels;
        m_summary.features.push_back(auxiliary_name(present[f].kind));
        m_summary.scales.push_back(scale);
    }
    if (m_channels > 0)
        m_summary.frames = m_frames;
}

void FeatureGuide::read_feature(const Feature& feature, int row_begin, int row_end, std::vector<float>& values) const
{
    const size_t samples = static_cast<size_t>(m_shape.width) * (row_end - row_begin) * feature.channels;
    std::vector<std::vector<float>> per_frame(m_frames.size(), std::vector<float>(samples));
    tbb::parallel_for(0, static_cast<int>(m_frames.size()), [&](int k) {
        m_source.read_auxiliary_rows(feature.kind, m_frames[static_cast<size_t>(k)], row_begin, row_end,
                                     per_frame[static_cast<size_t>(k)].data());
        if (feature.kind == Auxiliary::Depth)
            for (float& value : per_frame[static_cast<size_t>(k)])
                value = guided_depth(value);
    });
    values.assign(samples, 0.0f);
    const float share = 1.0f / static_cast<float>(m_frames.size());
    for (const std::vector<float>& frame : per_frame)  // frame order: the same bits for any thread count
        for (size_t i = 0; i < samples; ++i)
            values[i] += (std::isfinite(frame[i]) ? frame[i] : 0.0f) * share;
}

void FeatureGuide::read_rows(int row_begin, int row_end, std::vector<float>& features) const
{
    const std::int64_t pixels = static_cast<std::int64_t>(m_shape.width) * (row_end - row_begin);
    features.assign(static_cast<size_t>(pixels * m_channels), 0.0f);
    std::vector<float> values;
    int offset = 0;
    for (const Feature& feature : m_features) {
        read_feature(feature, row_begin, row_end, values);
        const float inverse_scale = static_cast<float>(1.0 / feature.scale);
        for (std::int64_t p = 0; p < pixels; ++p)
            for (int c = 0; c < feature.channels; ++c)
                features[static_cast<size_t>(p * m_channels + offset + c)] =
                    values[static_cast<size_t>(p * feature.channels + c)] * inverse_scale;
        offset += feature.channels;
    }
}

}  // namespace modestack::denoise
