// Error figures of a test image against its reference (see image_error.h).
#include "core/metrics/image_error.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace modestack::metrics {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
// Pixels per chunk of the fixed partition. The partition, not the scheduler,
// decides the order of the floating-point sums, so results never depend on
// how many threads run the chunks.
constexpr std::int64_t kChunkPixels = 8192;

enum class PairKind { Finite, SameNonFinite, Mismatch };

// NaN against NaN or +inf against +inf is "the same value" (a render that
// reproduces its reference's NaN is not wrong); any other non-finite pair is an
// infinitely large error.
PairKind classify(float test, float reference)
{
    if (std::isfinite(test) && std::isfinite(reference))
        return PairKind::Finite;
    if ((std::isnan(test) && std::isnan(reference)) || test == reference)
        return PairKind::SameNonFinite;
    return PairKind::Mismatch;
}

double ratio(double sum, std::int64_t count)
{
    return count > 0 ? sum / static_cast<double>(count) : 0.0;
}

std::int64_t chunk_count(std::int64_t pixel_count)
{
    return (pixel_count + kChunkPixels - 1) / kChunkPixels;
}

ErrorSums chunk_errors(const float* test, const float* reference, std::int64_t pixel_begin,
                       std::int64_t pixel_end, int channels, const PixelThresholds& thresholds)
{
    ErrorSums sums;
    for (std::int64_t pixel = pixel_begin; pixel < pixel_end; ++pixel) {
        double pixel_error = 0.0;
        for (int c = 0; c < channels; ++c) {
            std::int64_t index = pixel * channels + c;
            float x = test[index];
            float r = reference[index];
            switch (classify(x, r)) {
            case PairKind::Finite: {
                double difference = static_cast<double>(x) - static_cast<double>(r);
                double reference_value = r;
                sums.squared_relative +=
                    difference * difference / (reference_value * reference_value + kRelativeEpsilon);
                double tonemapped = tonemap_for_psnr(x) - tonemap_for_psnr(r);
                sums.squared_tonemapped += tonemapped * tonemapped;
                sums.absolute += std::abs(difference);
                pixel_error = std::max(pixel_error, std::abs(difference));
                break;
            }
            case PairKind::SameNonFinite:
                break;
            case PairKind::Mismatch:
                ++sums.non_finite;
                sums.squared_relative += kInfinity;
                sums.absolute += kInfinity;
                // Tonemapped values live in [0, 1]: a difference of 1 is the worst possible.
                sums.squared_tonemapped += 1.0;
                pixel_error = kInfinity;
                break;
            }
        }
        sums.values += channels;
        ++sums.pixels;
        if (pixel_error > thresholds.fail)
            ++sums.pixels_failing;
        if (pixel_error > thresholds.warn)
            ++sums.pixels_warning;
        sums.max_absolute = std::max(sums.max_absolute, pixel_error);
    }
    return sums;
}

double flicker_term(float test, float reference, float previous_test, float previous_reference)
{
    PairKind now = classify(test, reference);
    PairKind before = classify(previous_test, previous_reference);
    if (now == PairKind::Mismatch || before == PairKind::Mismatch)
        return kInfinity;
    if (now != PairKind::Finite || before != PairKind::Finite)
        return 0.0;
    double test_change = static_cast<double>(test) - static_cast<double>(previous_test);
    double reference_change = static_cast<double>(reference) - static_cast<double>(previous_reference);
    double reference_mean = 0.5 * (static_cast<double>(reference) + static_cast<double>(previous_reference));
    double error = test_change - reference_change;
    return error * error / (reference_mean * reference_mean + kRelativeEpsilon);
}

} // namespace

void ErrorSums::merge(const ErrorSums& other)
{
    values += other.values;
    pixels += other.pixels;
    squared_relative += other.squared_relative;
    squared_tonemapped += other.squared_tonemapped;
    absolute += other.absolute;
    max_absolute = std::max(max_absolute, other.max_absolute);
    pixels_failing += other.pixels_failing;
    pixels_warning += other.pixels_warning;
    non_finite += other.non_finite;
    flicker_values += other.flicker_values;
    flicker += other.flicker;
}

double ErrorSums::relative_mse() const
{
    return ratio(squared_relative, values);
}
double ErrorSums::tonemapped_mse() const
{
    return ratio(squared_tonemapped, values);
}
double ErrorSums::psnr() const
{
    double mse = tonemapped_mse();
    return mse > 0.0 ? 10.0 * std::log10(1.0 / mse) : kInfinity;
}
double ErrorSums::mean_absolute() const
{
    return ratio(absolute, values);
}
double ErrorSums::percent_failing() const
{
    return 100.0 * ratio(static_cast<double>(pixels_failing), pixels);
}
double ErrorSums::percent_warning() const
{
    return 100.0 * ratio(static_cast<double>(pixels_warning), pixels);
}
double ErrorSums::mean_flicker() const
{
    return flicker_values > 0 ? flicker / static_cast<double>(flicker_values)
                              : std::numeric_limits<double>::quiet_NaN();
}

double tonemap_for_psnr(double value)
{
    if (std::isnan(value))
        return value;
    if (value <= 0.0)
        return 0.0;
    if (std::isinf(value))
        return 1.0;
    return std::min(1.0, std::pow(value / (1.0 + value), 1.0 / kPsnrGamma));
}

ErrorSums frame_errors(const float* test, const float* reference, std::int64_t pixel_count, int channels,
                       const PixelThresholds& thresholds)
{
    std::vector<ErrorSums> partial(static_cast<size_t>(chunk_count(pixel_count)));
    tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, chunk_count(pixel_count), 1),
                      [&](const tbb::blocked_range<std::int64_t>& chunks) {
                          for (std::int64_t chunk = chunks.begin(); chunk < chunks.end(); ++chunk) {
                              std::int64_t begin = chunk * kChunkPixels;
                              std::int64_t end = std::min(pixel_count, begin + kChunkPixels);
                              partial[static_cast<size_t>(chunk)] =
                                  chunk_errors(test, reference, begin, end, channels, thresholds);
                          }
                      });
    ErrorSums sums;
    for (const ErrorSums& chunk : partial)
        sums.merge(chunk);
    return sums;
}

void add_flicker(const float* test, const float* reference, const float* previous_test,
                 const float* previous_reference, std::int64_t value_count, ErrorSums& sums)
{
    std::int64_t chunk_values = kChunkPixels * 4;
    std::int64_t chunks = (value_count + chunk_values - 1) / chunk_values;
    std::vector<double> partial(static_cast<size_t>(chunks), 0.0);
    tbb::parallel_for(
        tbb::blocked_range<std::int64_t>(0, chunks, 1), [&](const tbb::blocked_range<std::int64_t>& range) {
            for (std::int64_t chunk = range.begin(); chunk < range.end(); ++chunk) {
                double sum = 0.0;
                std::int64_t end = std::min(value_count, (chunk + 1) * chunk_values);
                for (std::int64_t i = chunk * chunk_values; i < end; ++i)
                    sum += flicker_term(test[i], reference[i], previous_test[i], previous_reference[i]);
                partial[static_cast<size_t>(chunk)] = sum;
            }
        });
    for (double chunk_sum : partial)
        sums.flicker += chunk_sum;
    sums.flicker_values += value_count;
}

} // namespace modestack::metrics
