#include "app/report/report_collector.h"

#include "core/denoise/estimator_choice.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace modestack::app::report {

int box_factor(int width, int largest)
{
    largest = std::max(1, largest);
    return std::max(1, (width + largest - 1) / largest);
}

BoxImage::BoxImage(int width, int height, int channels, int factor)
    : m_width(width), m_height(height), m_channels(channels), m_factor(std::max(1, factor)),
      m_small_width((width + m_factor - 1) / m_factor), m_small_height((height + m_factor - 1) / m_factor),
      m_sums(static_cast<size_t>(m_small_width) * m_small_height * 3, 0.0f)
{
}

void BoxImage::add_row(int row, const float* values)
{
    float* destination = m_sums.data() + static_cast<size_t>(row / m_factor) * m_small_width * 3;
    for (int x = 0; x < m_width; ++x) {
        float* box = destination + (x / m_factor) * 3;
        for (int c = 0; c < 3; ++c) {
            // One or two channels (a luminance layer) show as grey.
            float value = values[static_cast<size_t>(x) * m_channels + std::min(c, m_channels - 1)];
            box[c] += std::isfinite(value) ? value : 0.0f;
        }
    }
}

LinearImage BoxImage::mean() const
{
    LinearImage image{m_small_width, m_small_height, m_sums};
    for (int y = 0; y < m_small_height; ++y) {
        int box_height = std::min(m_factor, m_height - y * m_factor);
        for (int x = 0; x < m_small_width; ++x) {
            int box_width = std::min(m_factor, m_width - x * m_factor);
            float scale = 1.0f / static_cast<float>(box_width * box_height);
            for (int c = 0; c < 3; ++c)
                image.rgb[(static_cast<size_t>(y) * m_small_width + x) * 3 + c] *= scale;
        }
    }
    return image;
}

class Collector::Source : public denoise::ForwardingSource {
public:
    Source(denoise::FrameSource& inner, Collector& collector) : ForwardingSource(inner), m_collector(collector) {}
    void read_rows(int frame_index, int row_begin, int row_end, float* destination,
                   denoise::PassThroughRows* pass_through) override
    {
        m_inner.read_rows(frame_index, row_begin, row_end, destination, pass_through);
        m_collector.take_source_rows(frame_index, row_begin, row_end, destination);
    }

private:
    Collector& m_collector;
};

class Collector::Sink : public denoise::ForwardingSink {
public:
    Sink(denoise::FrameSink& inner, Collector& collector) : ForwardingSink(inner), m_collector(collector) {}
    void write_rows(int frame_index, int row_begin, int row_end, const float* rebuilt, const float* sigma,
                    const denoise::PassThroughRows* pass_through) override
    {
        m_collector.take_sink_rows(frame_index, row_begin, row_end, rebuilt, sigma);
        m_inner.write_rows(frame_index, row_begin, row_end, rebuilt, sigma, pass_through);
    }
    void write_choice_rows(int frame_index, int row_begin, int row_end, const std::uint8_t* chosen) override
    {
        m_collector.take_choice_rows(frame_index, row_begin, row_end, chosen);
        m_inner.write_choice_rows(frame_index, row_begin, row_end, chosen);
    }

private:
    Collector& m_collector;
};

Collector::Collector(denoise::FrameSource& source, denoise::FrameSink& sink, CollectorOptions options)
    : m_options(std::move(options)), m_shape(source.shape())
{
    const int frames = std::max(0, m_shape.frames);
    m_preview_factor = box_factor(m_shape.width, m_options.preview_width);
    auto stack_bytes = [&](int factor) {
        std::int64_t small_width = (m_shape.width + factor - 1) / factor, small_height = (m_shape.height + factor - 1) / factor;
        return small_width * small_height * 3 * std::int64_t(sizeof(float)) * frames;
    };
    while (stack_bytes(m_preview_factor) > m_options.max_stack_bytes && m_preview_factor < m_shape.width)
        ++m_preview_factor;
    m_panel_factor = box_factor(m_shape.width, m_options.panel_width);
    m_frame_locks = std::make_unique<std::mutex[]>(static_cast<size_t>(frames));
    m_rows_read.assign(frames, std::vector<bool>(std::max(0, m_shape.height), false));
    m_rows_written = m_rows_read;
    m_error_sums.assign(frames, 0.0);
    m_error_samples.assign(frames, 0);
    m_shown_slot.assign(frames, -1);
    for (int t = 0; t < frames; ++t)
        m_stack.emplace_back(m_shape.width, m_shape.height, m_shape.channels, m_preview_factor);
    std::vector<int> shown;
    for (int index : m_options.shown_indices)
        if (index >= 0 && index < frames && m_shown_slot[index] < 0) {
            m_shown_slot[index] = static_cast<int>(m_shown.size());
            shown.push_back(index);
            BoxImage image(m_shape.width, m_shape.height, m_shape.channels, m_panel_factor);
            Shown slot{image, image, BoxImage(m_shape.width, m_shape.height, 1, m_panel_factor),
                       BoxImage(m_shape.width, m_shape.height, 3, m_panel_factor),
                       std::vector<bool>(static_cast<size_t>(std::max(0, m_shape.height)), false)};
            m_shown.push_back(std::move(slot));
        }
    m_options.shown_indices = shown;
    m_source = std::make_unique<Source>(source, *this);
    m_sink = std::make_unique<Sink>(sink, *this);
}

Collector::~Collector() = default;

denoise::FrameSource& Collector::source() { return *m_source; }
denoise::FrameSink& Collector::sink() { return *m_sink; }

void Collector::take_source_rows(int frame_index, int row_begin, int row_end, const float* rows)
{
    std::lock_guard<std::mutex> lock(m_frame_locks[frame_index]);
    const size_t row_samples = static_cast<size_t>(m_shape.width) * m_shape.channels;
    const int slot = m_shown_slot[frame_index];
    for (int row = row_begin; row < row_end; ++row) {
        if (m_rows_read[frame_index][row])
            continue;
        m_rows_read[frame_index][row] = true;
        const float* values = rows + (row - row_begin) * row_samples;
        m_stack[frame_index].add_row(row, values);
        if (slot >= 0)
            m_shown[slot].noisy.add_row(row, values);
    }
}

void Collector::take_sink_rows(int frame_index, int row_begin, int row_end, const float* rebuilt, const float* sigma)
{
    std::lock_guard<std::mutex> lock(m_frame_locks[frame_index]);
    const size_t row_samples = static_cast<size_t>(m_shape.width) * m_shape.channels;
    const int slot = m_shown_slot[frame_index];
    const int shown_channels = std::min(3, m_shape.channels);
    for (int row = row_begin; row < row_end; ++row) {
        if (m_rows_written[frame_index][row])
            continue;
        m_rows_written[frame_index][row] = true;
        const float* values = rebuilt + (row - row_begin) * row_samples;
        const float* spreads = sigma + (row - row_begin) * row_samples;
        double sum = 0;
        for (int x = 0; x < m_shape.width; ++x)
            for (int c = 0; c < shown_channels; ++c) {
                double value = values[static_cast<size_t>(x) * m_shape.channels + c];
                double spread = spreads[static_cast<size_t>(x) * m_shape.channels + c];
                if (std::isfinite(value) && std::isfinite(spread))
                    sum += spread * spread / (value * value + 0.01);
            }
        m_error_sums[frame_index] += sum;
        m_error_samples[frame_index] += static_cast<std::int64_t>(m_shape.width) * shown_channels;
        if (slot >= 0) {
            m_shown[slot].denoised.add_row(row, values);
            std::vector<float> mean_spread(m_shape.width, 0.0f);
            for (int x = 0; x < m_shape.width; ++x) {
                for (int c = 0; c < shown_channels; ++c)
                    mean_spread[x] += spreads[static_cast<size_t>(x) * m_shape.channels + c];
                mean_spread[x] /= static_cast<float>(shown_channels);
            }
            m_shown[slot].sigma.add_row(row, mean_spread.data());
        }
    }
}

namespace {
// The estimator map's colour of each Estimator (estimator_choice.h): the
// rebuild grey, the input red, the 1 px and 2 px blurs green and blue, the
// non-local means yellow.
constexpr std::array<std::array<float, 3>, denoise::kEstimators> kEstimatorColours{
    {{0.35f, 0.35f, 0.35f}, {1.0f, 0.0f, 0.0f}, {0.0f, 0.8f, 0.0f}, {0.0f, 0.3f, 1.0f}, {1.0f, 0.85f, 0.0f}}};
} // namespace

const char* const kEstimatorMapLabel =
    "estimator map (grey: rebuild, red: input, green: 1 px blur, blue: 2 px blur, yellow: non-local means)";

void Collector::take_choice_rows(int frame_index, int row_begin, int row_end, const std::uint8_t* chosen)
{
    const int slot = m_shown_slot[frame_index];
    if (slot < 0)
        return;
    std::lock_guard<std::mutex> lock(m_frame_locks[frame_index]);
    Shown& shown = m_shown[slot];
    shown.any_chosen = true;
    std::vector<float> colours(static_cast<size_t>(m_shape.width) * 3);
    for (int row = row_begin; row < row_end; ++row) {
        if (shown.rows_chosen[row])
            continue;
        shown.rows_chosen[row] = true;
        for (int x = 0; x < m_shape.width; ++x) {
            const std::uint8_t estimator = chosen[static_cast<size_t>(row - row_begin) * m_shape.width + x];
            const auto& colour = kEstimatorColours[std::min<size_t>(estimator, denoise::kEstimators - 1)];
            std::copy(colour.begin(), colour.end(), colours.begin() + 3 * x);
        }
        shown.chosen.add_row(row, colours.data());
    }
}

std::vector<double> Collector::estimated_error() const
{
    std::vector<double> errors(m_error_sums.size(), std::numeric_limits<double>::quiet_NaN());
    for (size_t t = 0; t < errors.size(); ++t)
        if (m_error_samples[t] > 0)
            errors[t] = m_error_sums[t] / static_cast<double>(m_error_samples[t]);
    return errors;
}

std::vector<LinearImage> Collector::coefficient_images(int first, const std::vector<std::vector<double>>& modes) const
{
    std::vector<LinearImage> means;
    const int count = modes.empty() ? 0 : static_cast<int>(modes.front().size());
    for (int t = 0; t < count; ++t)
        means.push_back(m_stack.at(static_cast<size_t>(first + t)).mean());
    std::vector<LinearImage> images(modes.size());
    if (means.empty())
        return images;
    // One mode per task, frames summed in order: the same bytes for any thread count.
    tbb::parallel_for(0, static_cast<int>(modes.size()), [&](int j) {
        LinearImage& image = images[j];
        image.width = means.front().width;
        image.height = means.front().height;
        std::vector<double> sum(means.front().rgb.size(), 0.0);
        for (int t = 0; t < count; ++t) {
            const double weight = modes[j][t];
            const std::vector<float>& values = means[t].rgb;
            for (size_t i = 0; i < sum.size(); ++i)
                sum[i] += weight * values[i];
        }
        image.rgb.assign(sum.begin(), sum.end());
    });
    return images;
}

std::vector<ShownFrame> Collector::shown_frames(const std::vector<int>& frame_numbers) const
{
    std::vector<ShownFrame> frames;
    for (size_t k = 0; k < m_shown.size(); ++k) {
        int index = m_options.shown_indices[k];
        ShownFrame frame;
        frame.index = index;
        frame.number = index < static_cast<int>(frame_numbers.size()) ? frame_numbers[index] : index;
        frame.panels.push_back({"noisy", m_shown[k].noisy.mean()});
        frame.panels.push_back({"denoised", m_shown[k].denoised.mean()});
        frame.panels.push_back({"sigma", m_shown[k].sigma.mean()});
        if (m_shown[k].any_chosen)
            frame.panels.push_back({kEstimatorMapLabel, m_shown[k].chosen.mean(), true});
        frames.push_back(std::move(frame));
    }
    return frames;
}

}  // namespace modestack::app::report
