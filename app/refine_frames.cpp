#include "app/refine_frames.h"

#include "app/command.h"
#include "core/common/error.h"
#include "core/refine/blend.h"
#include "core/refine/selection.h"
#include "io/frame_header.h"
#include "io/layers.h"

#include <fmt/format.h>

#include <chrono>
#include <optional>

namespace modestack::app {
namespace {

bool layer_is(const std::string& layer, const std::string& wanted)
{
    return layer == wanted || (layer.size() > wanted.size() &&
                               layer.compare(layer.size() - wanted.size(), wanted.size(), wanted) == 0 &&
                               layer[layer.size() - wanted.size() - 1] == '.');
}

// Whether any part of the frame has layer `wanted` (any prefix, layer_is).
bool has_layer(const io::FrameHeader& header, const std::string& wanted)
{
    for (const auto& group : io::group_layers(io::channels_as_read(header))) // every part's
        if (layer_is(group.name, wanted))
            return true;
    return false;
}

} // namespace

void check_sigma_channels(const std::string& file, const std::string& layer)
{
    if (!has_layer(io::read_frame_header(file), layer + ".sigma"))
        throw bad_input(file,
                        fmt::format("no {}.sigma channels: refine needs the output of 'modestack denoise "
                                    "--layer {}'",
                                    layer, layer));
}

void check_colour_layers(const io::SequenceReader& reader)
{
    for (const auto& layer : reader.layers())
        if (layer.channel_names.size() != 3)
            throw bad_input(reader.sequence().files.front(),
                            fmt::format("layer {} must have R, G and B channels", layer.name));
}

LayerAndSigma::LayerAndSigma(std::size_t pixel_count)
    : pixels(pixel_count), rows(pixel_count * 6), value(pixel_count * 3), sigma(pixel_count * 3)
{
}

void LayerAndSigma::read(const io::SequenceReader& reader, int frame_index)
{
    reader.read_selected(frame_index, 0, reader.height(), rows.data());
    split_rows();
}

void LayerAndSigma::from_native(const io::SequenceReader& reader, int frame_index,
                                const unsigned char* native)
{
    reader.selected_from_native(frame_index, native, pixels, rows.data());
    split_rows();
}

void LayerAndSigma::split_rows()
{
    for (std::size_t p = 0; p < pixels; ++p)
        for (int c = 0; c < 3; ++c) {
            value[p * 3 + c] = rows[p * 6 + c];
            sigma[p * 3 + c] = rows[p * 6 + 3 + c];
        }
}

void LayerAndSigma::store()
{
    for (std::size_t p = 0; p < pixels; ++p)
        for (int c = 0; c < 3; ++c) {
            rows[p * 6 + c] = value[p * 3 + c];
            rows[p * 6 + 3 + c] = sigma[p * 3 + c];
        }
}

float budget_threshold(const io::SequenceReader& reader, double budget_percent, float dark_floor,
                       Progress& progress, double& seconds)
{
    auto start = std::chrono::steady_clock::now();
    const std::size_t pixels = static_cast<std::size_t>(reader.width()) * reader.height();
    refine::ScoreHistogram histogram;
    LayerAndSigma frame(pixels);
    std::vector<float> scores(pixels);
    progress.begin("scoring the denoised frames", reader.frame_count());
    for (int i = 0; i < reader.frame_count(); ++i) {
        throw_if_cancelled();
        frame.read(reader, i);
        refine::relative_error_scores(frame.value.data(), frame.sigma.data(), pixels, 3, dark_floor,
                                      scores.data());
        histogram.add(scores.data(), pixels);
        progress.advance();
    }
    progress.end();
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return histogram.threshold_for_fraction(budget_percent / 100.0);
}

float gain_threshold_of_shot(const io::SequenceReader& reader, const refine::RefineSettings& settings,
                             Progress& progress, double& seconds)
{
    auto start = std::chrono::steady_clock::now();
    const std::size_t pixels = static_cast<std::size_t>(reader.width()) * reader.height();
    LayerAndSigma frame(pixels);
    double sum = 0;
    progress.begin("estimating the shot's error", reader.frame_count());
    for (int i = 0; i < reader.frame_count(); ++i) {
        throw_if_cancelled();
        frame.read(reader, i);
        sum += refine::estimated_relative_mse(frame.value.data(), frame.sigma.data(), pixels, 3,
                                              settings.dark_floor);
        progress.advance();
    }
    progress.end();
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return refine::gain_threshold(sum / reader.frame_count(), settings.input_spp, settings.render.spp);
}

int recorded_input_spp(const std::string& file, const std::string& layer)
{
    const io::FrameHeader header = io::read_frame_header(file);
    if (!has_layer(header, layer + "Var"))
        throw bad_input(file,
                        fmt::format("no {}Var channels (the input's variance): refine chooses pixels by "
                                    "gain from them; pass --threshold or --budget",
                                    layer));
    const std::optional<std::string> value = io::find_attribute(header, "modestack:spp");
    if (!value)
        throw bad_input(file, "no modestack:spp attribute (the input's samples per pixel): refine chooses "
                              "pixels by gain from it; pass --threshold or --budget");
    const std::optional<std::int64_t> spp = io::attribute_count(*value, 1'000'000'000);
    if (!spp)
        throw bad_input(file, fmt::format("modestack:spp is {}: not a sample count", *value));
    return static_cast<int>(*spp);
}

void add_mask_output(std::vector<std::unique_ptr<io::FrameOutput>>& outputs, const std::string& file,
                     const std::vector<float>& weights, int width, int height,
                     const std::vector<io::HeaderAttribute>& attributes)
{
    io::NewImageDescription image;
    image.width = width;
    image.height = height;
    image.channel_names = {"mask", "weight"};
    image.channel_types = {"half", "float"};
    std::vector<float> mask_pixels(weights.size() * 2);
    for (std::size_t p = 0; p < weights.size(); ++p) {
        mask_pixels[p * 2] = weights[p] > 0 ? 1.0f : 0.0f;
        mask_pixels[p * 2 + 1] = weights[p];
    }
    outputs.push_back(std::make_unique<io::FrameOutput>(file, image, attributes));
    outputs.back()->write_float_rows(0, height, mask_pixels.data());
}

} // namespace modestack::app
