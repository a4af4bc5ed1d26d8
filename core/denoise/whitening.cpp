#include "core/denoise/whitening.h"

#include "core/common/error.h"
#include "core/common/progress.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace modestack::denoise {
namespace {

// One layer's variance as the whole-selection Variance of a shot of that layer's channels.
class LayerVarianceView : public FrameSource {
public:
    LayerVarianceView(FrameSource& source, int layer, int channels)
        : m_source(source), m_layer(layer), m_shape(source.shape())
    {
        m_shape.channels = channels;
    }
    ShotShape shape() const override { return m_shape; }
    void read_rows(int, int, int, float*, PassThroughRows*) override
    {
        throw internal_error("a layer's variance view has no rows of its own");
    }
    int auxiliary_channels(Auxiliary kind) const override
    {
        return kind == Auxiliary::Variance ? m_source.layer_variance_channels(m_layer) : 0;
    }
    void read_auxiliary_rows(Auxiliary kind, int frame_index, int row_begin, int row_end,
                             float* destination) override
    {
        if (kind != Auxiliary::Variance)
            throw internal_error("a layer's variance view has no guides");
        m_source.read_layer_variance_rows(m_layer, frame_index, row_begin, row_end, destination);
    }

private:
    FrameSource& m_source;
    int m_layer;
    ShotShape m_shape;
};

} // namespace

WhiteningWeights layer_whitening_weights(FrameSource& source, int layer, int channels,
                                         const WhiteningOptions& options)
{
    LayerVarianceView view(source, layer, channels);
    return whitening_weights(view, options);
}

WhiteningWeights whitening_weights(FrameSource& source, const WhiteningOptions& options)
{
    const ShotShape shape = source.shape();
    if (source.auxiliary_channels(Auxiliary::Variance) != shape.channels)
        throw internal_error("noise whitening needs one variance channel per selected channel");
    const std::int64_t row_samples = static_cast<std::int64_t>(shape.width) * shape.channels;
    const std::int64_t samples = row_samples * shape.height;
    // Sum over frames, one frame after another (fixed order: the same bits for any thread count).
    std::vector<double> sum(static_cast<size_t>(samples), 0.0);
    std::vector<float> frame(static_cast<size_t>(samples));
    for (int t = 0; t < shape.frames; ++t) {
        throw_if_cancelled();
        source.read_auxiliary_rows(Auxiliary::Variance, t, 0, shape.height, frame.data());
        for (std::int64_t i = 0; i < samples; ++i) {
            const float value = frame[static_cast<size_t>(i)];
            if (!std::isfinite(value) || value < 0)
                throw bad_input("the variance layer",
                                fmt::format("frame {} holds a variance of {}: it must be finite and at least 0",
                                            t + 1, value));
            sum[static_cast<size_t>(i)] += value;
        }
    }
    WhiteningWeights result;
    double total = 0;
    for (double value : sum)
        total += value;
    result.mean_variance = samples > 0 ? total / (static_cast<double>(samples) * shape.frames) : 0.0;
    result.floor = std::max(options.floor_fraction * result.mean_variance, 1e-30);
    // Mean over time, pooled over the (2r + 1)² window clipped to the image, per channel.
    result.weights.resize(static_cast<size_t>(samples));
    const int radius = options.pool_radius;
    tbb::parallel_for(0, shape.height, [&](int y) {
        for (int x = 0; x < shape.width; ++x)
            for (int c = 0; c < shape.channels; ++c) {
                double pooled = 0;
                int count = 0;
                for (int v = std::max(0, y - radius); v <= std::min(shape.height - 1, y + radius); ++v)
                    for (int u = std::max(0, x - radius); u <= std::min(shape.width - 1, x + radius); ++u, ++count)
                        pooled += sum[static_cast<size_t>(v * row_samples + u * shape.channels + c)];
                const double variance = pooled / (static_cast<double>(count) * shape.frames);
                result.weights[static_cast<size_t>(y * row_samples + x * shape.channels + c)] =
                    static_cast<float>(1.0 / std::sqrt(std::max(variance, result.floor)));
            }
    });
    double weight_sum = 0;
    for (float w : result.weights)
        weight_sum += w;
    const double scale = samples > 0 ? static_cast<double>(samples) / weight_sum : 1.0;
    result.smallest = 1e300, result.largest = 0;
    const float ceiling = static_cast<float>(1.0 / std::sqrt(result.floor));
    for (float& w : result.weights) {
        if (w >= ceiling)
            ++result.floored_samples;
        w = static_cast<float>(w * scale);
        result.smallest = std::min(result.smallest, static_cast<double>(w));
        result.largest = std::max(result.largest, static_cast<double>(w));
    }
    return result;
}

}  // namespace modestack::denoise
