#include "core/denoise/guided_filter.h"

#include "core/common/avx2_clones.h"
#include "core/common/error.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdlib>

namespace modestack::denoise {
namespace {

// The images that share one candidate: one set of weights.
struct Kernel {
    FilterCandidate candidate;
    int radius = 0;
    std::vector<float> spatial;
    ExponentScales scales;
    std::vector<const GuidedImage*> images;
};

std::vector<Kernel> group_by_candidate(const Guide& guide, const std::vector<GuidedImage>& images)
{
    std::vector<Kernel> kernels;
    for (const GuidedImage& image : images) {
        const FilterCandidate& candidate = image.candidate;
        auto same = std::find_if(kernels.begin(), kernels.end(), [&](const Kernel& kernel) {
            return kernel.candidate.width == candidate.width && kernel.candidate.range == candidate.range &&
                   kernel.candidate.feature_range == candidate.feature_range;
        });
        if (same == kernels.end()) {
            Kernel kernel;
            kernel.candidate = candidate;
            kernel.radius = kernel_radius(candidate.width);
            kernel.spatial = spatial_weights(candidate.width);
            kernel.scales = exponent_scales(candidate, guide);
            if (kernel.radius <= 0 || (kernel.scales.range == 0 && kernel.scales.feature == 0))
                throw internal_error("guided_filter: a candidate without width or guide term");
            kernels.push_back(std::move(kernel));
            same = kernels.end() - 1;
        }
        same->images.push_back(&image);
    }
    return kernels;
}

// One output row's accumulators.
struct RowSums {
    std::vector<float> range, feature, weight, spread;  // the current offset's
    std::vector<float> zeros;
    std::vector<std::vector<float>> sum, squares;        // per kernel, per pixel
    std::vector<std::vector<float>> weighted;            // per image: Σ w · image, per sample
};

struct Filter {
    const Guide& guide;
    const std::vector<GuidedImage>& images;
    std::vector<Kernel> kernels;
    int widest = 0;
    bool any_range = false, any_feature = false;
};

// Output row y of every image.
MODESTACK_AVX2_CLONES void filter_row(const Filter& filter, int y, int valid_y0, RowSums& row)
{
    const Guide& guide = filter.guide;
    const std::vector<GuidedImage>& images = filter.images;
    const std::vector<Kernel>& kernels = filter.kernels;
    const int width = guide.width, channels = guide.channels, widest = filter.widest;
    const std::int64_t row_length = static_cast<std::int64_t>(width) * channels;
    for (std::vector<float>& values : row.sum)
        std::fill(values.begin(), values.end(), 0.0f);
    for (std::vector<float>& values : row.squares)
        std::fill(values.begin(), values.end(), 0.0f);
    for (std::vector<float>& values : row.weighted)
        std::fill(values.begin(), values.end(), 0.0f);
    const std::int64_t centre_row = static_cast<std::int64_t>(y) * width;
    for (int qy = std::max(0, y - widest); qy <= std::min(guide.height - 1, y + widest); ++qy) {
        const int dy = qy - y;
        for (int dx = -widest; dx <= widest; ++dx) {
            const int x_begin = std::max(0, -dx), x_end = std::min(width, width - dx);
            if (x_begin >= x_end)
                continue;
            const std::int64_t other_row = static_cast<std::int64_t>(qy) * width + dx;
            float* const range = row.range.data();
            float* const feature = row.feature.data();
            if (filter.any_range) {
                std::fill(range + x_begin, range + x_end, 0.0f);
                for (int c = 0; c < channels; ++c) {
                    const float* value = guide.value_plane(c);
                    const float* noise = guide.noise_plane(c);
                    for (int x = x_begin; x < x_end; ++x)
                        range[x] += range_term(value[centre_row + x], value[other_row + x], noise[centre_row + x],
                                               noise[other_row + x]);
                }
            }
            if (filter.any_feature) {
                std::fill(feature + x_begin, feature + x_end, 0.0f);
                for (int k = 0; k < guide.feature_channels; ++k) {
                    const float* plane = guide.feature_plane(k);
                    for (int x = x_begin; x < x_end; ++x)
                        feature[x] += feature_term(plane[centre_row + x], plane[other_row + x]);
                }
            }
            for (std::size_t n = 0; n < kernels.size(); ++n) {
                const Kernel& kernel = kernels[n];
                if (std::abs(dx) > kernel.radius || std::abs(dy) > kernel.radius)
                    continue;
                const float spatial = kernel.spatial[static_cast<std::size_t>(dx * dx + dy * dy)];
                float* const weight = row.weight.data();
                float* const sum = row.sum[n].data();
                float* const squares = row.squares[n].data();
                // A term the kernel lacks reads zeros (guided_exponent), as in the
                // survey's window.
                const ExponentScales scales = kernel.scales;
                const float* const range_in = scales.range != 0 ? range : row.zeros.data();
                const float* const feature_in = scales.feature != 0 ? feature : row.zeros.data();
                for (int x = x_begin; x < x_end; ++x) {
                    const float w = spatial * weight_exp(guided_exponent(scales, range_in[x], feature_in[x]));
                    weight[x] = w;
                    sum[x] += w;
                    squares[x] += w * w;
                }
                // The weights spread over the channels, so that each image's
                // update is one contiguous run.
                // The common channel counts have loops of their own: with the
                // count unknown the copy ran one value at a time (a third of
                // this function's time on RGB).
                float* const spread = row.spread.data();
                if (channels == 1)
                    std::copy(weight + x_begin, weight + x_end, spread + x_begin);
                else if (channels == 3)
                    for (int x = x_begin; x < x_end; ++x)
                        spread[3 * x] = spread[3 * x + 1] = spread[3 * x + 2] = weight[x];
                else
                    for (int x = x_begin; x < x_end; ++x)
                        for (int c = 0; c < channels; ++c)
                            spread[x * channels + c] = weight[x];
                const std::int64_t k_begin = static_cast<std::int64_t>(x_begin) * channels;
                const std::int64_t k_end = static_cast<std::int64_t>(x_end) * channels;
                for (const GuidedImage* image : kernel.images) {
                    float* const out = row.weighted[static_cast<std::size_t>(image - images.data())].data();
                    const float* const source = image->image;
                    const std::int64_t shift = qy * row_length + static_cast<std::int64_t>(dx) * channels;
                    for (std::int64_t k = k_begin; k < k_end; ++k)
                        out[k] += spread[k] * source[k + shift];
                }
            }
        }
    }
    for (std::size_t n = 0; n < kernels.size(); ++n) {
        const std::vector<float>& sum = row.sum[n];
        const std::vector<float>& squares = row.squares[n];
        for (const GuidedImage* image : kernels[n].images) {
            const std::vector<float>& values = row.weighted[static_cast<std::size_t>(image - images.data())];
            float* out = image->filtered + static_cast<std::int64_t>(y - valid_y0) * row_length;
            float* gains = image->gains + static_cast<std::int64_t>(y - valid_y0) * width;
            for (int x = 0; x < width; ++x) {
                for (int c = 0; c < channels; ++c)
                    out[x * channels + c] = values[static_cast<std::size_t>(x * channels + c)] / sum[x];
                gains[x] = squares[x] / (sum[x] * sum[x]);
            }
        }
    }
}

}  // namespace

void guided_filter(const Guide& guide, int valid_y0, int valid_y1, const std::vector<GuidedImage>& images)
{
    if (images.empty())
        return;
    Filter filter{guide, images, group_by_candidate(guide, images)};
    for (const Kernel& kernel : filter.kernels) {
        filter.widest = std::max(filter.widest, kernel.radius);
        filter.any_range = filter.any_range || kernel.scales.range != 0;
        filter.any_feature = filter.any_feature || kernel.scales.feature != 0;
    }
    const std::size_t width = static_cast<std::size_t>(guide.width);
    const std::size_t row_length = width * static_cast<std::size_t>(guide.channels);
    tbb::parallel_for(tbb::blocked_range<int>(valid_y0, valid_y1), [&](const tbb::blocked_range<int>& rows) {
        RowSums row;  // sized once per task, cleared per row
        row.range.resize(width);
        row.feature.resize(width);
        row.weight.resize(width);
        row.zeros.assign(width, 0.0f);
        row.spread.resize(row_length);
        row.sum.assign(filter.kernels.size(), std::vector<float>(width));
        row.squares = row.sum;
        row.weighted.assign(images.size(), std::vector<float>(row_length));
        for (int y = rows.begin(); y < rows.end(); ++y)
            filter_row(filter, y, valid_y0, row);
    });
}

}  // namespace modestack::denoise
