#include "app/color_adapters.h"

#include "core/common/error.h"
#include "io/sequence_reader.h"

#include <fmt/format.h>

#include <vector>

namespace modestack::app {
namespace {

std::size_t row_triples(const denoise::ShotShape& shape, int row_begin, int row_end)
{
    return static_cast<std::size_t>(row_end - row_begin) * shape.width * (shape.channels / 3);
}

void check_triples(const denoise::ShotShape& shape)
{
    if (shape.channels % 3 != 0)
        throw internal_error(fmt::format(
            "colour conversion needs RGB layers, the source has {} channels per pixel", shape.channels));
}

} // namespace

LinearizingSource::LinearizingSource(denoise::FrameSource& inner, const io::ColorConverter& converter)
    : ForwardingSource(inner), m_converter(converter)
{
    check_triples(inner.shape());
}

void LinearizingSource::read_rows(int frame_index, int row_begin, int row_end, float* destination,
                                  denoise::PassThroughRows* pass_through)
{
    m_inner.read_rows(frame_index, row_begin, row_end, destination, pass_through);
    m_converter.to_scene_linear(destination, row_triples(m_inner.shape(), row_begin, row_end));
}

DelinearizingSink::DelinearizingSink(denoise::FrameSink& inner, const io::ColorConverter& converter,
                                     denoise::ShotShape shape)
    : ForwardingSink(inner), m_converter(converter), m_shape(shape)
{
    check_triples(shape);
}

void DelinearizingSink::write_rows(int frame_index, int row_begin, int row_end, const float* rebuilt,
                                   const float* sigma, const denoise::PassThroughRows* pass_through)
{
    std::size_t triples = row_triples(m_shape, row_begin, row_end);
    thread_local std::vector<float> encoded;
    encoded.assign(rebuilt, rebuilt + triples * 3);
    m_converter.from_scene_linear(encoded.data(), triples);
    m_inner.write_rows(frame_index, row_begin, row_end, encoded.data(), sigma, pass_through);
}

DenoiseColor choose_denoise_color(const std::string& ocio_config, const std::string& colorspace,
                                  const io::SequenceReader& reader)
{
    DenoiseColor color{io::ColorConfig(io::locate_color_config(ocio_config)), {}, {}, nullptr};
    color.scene_linear = color.config.scene_linear_space();
    if (!colorspace.empty())
        color.input = {color.config.find_color_space(colorspace, "--colorspace"), "--colorspace"};
    else
        color.input = io::recorded_color_space(reader, color.config);
    if (!color.config.is_scene_linear(color.input.space)) {
        color.converter = std::make_shared<io::ColorConverter>(color.config, color.input.space);
        if (color.converter->is_identity())
            color.converter.reset();
    }
    return color;
}

nlohmann::ordered_json color_json(const DenoiseColor& color)
{
    return {{"ocio_config", color.config.path()},
            {"ocio_config_name", color.config.name()},
            {"ocio_config_from", io::describe(color.config.source())},
            {"input_space", color.input.space},
            {"input_space_from", color.input.evidence},
            {"scene_linear", color.scene_linear},
            {"converted", color.converter != nullptr},
            {"sigma_space", color.scene_linear}};
}

void append_color_attributes(std::vector<io::HeaderAttribute>& attributes, const DenoiseColor& color)
{
    attributes.push_back(io::HeaderAttribute::of_text("modestack:ocio_config", color.config.path()));
    attributes.push_back(io::HeaderAttribute::of_text("modestack:colorspace", color.input.space));
    attributes.push_back(io::HeaderAttribute::of_text("modestack:denoised_in", color.scene_linear));
}

ColorStream::ColorStream(const DenoiseColor& color, denoise::FrameSource& source, denoise::FrameSink& sink)
    : m_source(source), m_sink(sink)
{
    if (!color.converter)
        return;
    m_linear_source.emplace(source, *color.converter);
    m_delinear_sink.emplace(sink, *color.converter, source.shape());
}

} // namespace modestack::app
