// Colour management around the denoise engine, which works on scene-linear
// light and knows nothing of colour spaces: decorators that convert the rows
// a FrameSource hands out to the config's scene_linear space and the rebuilt
// rows back to the input's own space before a FrameSink writes them, and the
// choice `denoise` makes (which config, which input space, whether to convert)
// with its JSON and EXR provenance. Sigma stays in scene-linear units: the
// standard error of a non-linearly encoded value has no single scale.
#pragma once

#include "core/denoise/frame_stream.h"
#include "io/color_management.h"
#include "io/frame_output.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace modestack::io {
class SequenceReader;
}

namespace modestack::app {

/// A FrameSource whose rows are another source's, converted to scene-linear.
class LinearizingSource : public denoise::ForwardingSource {
public:
    /// `inner` and `converter` must outlive this object; the source's channels
    /// must be whole RGB triples (3 per layer).
    LinearizingSource(denoise::FrameSource& inner, const io::ColorConverter& converter);
    void read_rows(int frame_index, int row_begin, int row_end, float* destination,
                   denoise::PassThroughRows* pass_through) override;

private:
    const io::ColorConverter& m_converter;
};

/// A FrameSink that converts rebuilt rows from scene-linear back to the input
/// space before forwarding them; sigma and the spatial modes pass unchanged
/// (they are differences and spreads, in scene-linear units).
class DelinearizingSink : public denoise::ForwardingSink {
public:
    /// `inner` and `converter` must outlive this object; `shape` is the source's.
    DelinearizingSink(denoise::FrameSink& inner, const io::ColorConverter& converter,
                      denoise::ShotShape shape);
    void write_rows(int frame_index, int row_begin, int row_end, const float* rebuilt, const float* sigma,
                    const denoise::PassThroughRows* pass_through) override;

private:
    const io::ColorConverter& m_converter;
    denoise::ShotShape m_shape;
};

/// What `denoise` decided about colour.
struct DenoiseColor {
    io::ColorConfig config;
    io::RecordedColorSpace input;                  ///< the input's space and how it was found
    std::string scene_linear;                      ///< the config's scene_linear space
    std::shared_ptr<io::ColorConverter> converter; ///< null: the input is scene-linear already
};

/// Loads the config (--ocio-config, $OCIO, shipped) and finds the input's
/// space: `colorspace` (--colorspace) when given, else what `reader`'s files
/// record. Throws a usage error listing the spaces for an unknown name, and
/// Error (bad input) for a broken config.
DenoiseColor choose_denoise_color(const std::string& ocio_config, const std::string& colorspace,
                                  const io::SequenceReader& reader);

/// The "color" block of the --json summary.
nlohmann::ordered_json color_json(const DenoiseColor& color);

/// Appends modestack:ocio_config, modestack:colorspace and
/// modestack:denoised_in to the provenance attributes.
void append_color_attributes(std::vector<io::HeaderAttribute>& attributes, const DenoiseColor& color);

/// The engine's two ends with the colour conversion in place when needed.
class ColorStream {
public:
    /// `source`, `sink` and `color` must outlive this object.
    ColorStream(const DenoiseColor& color, denoise::FrameSource& source, denoise::FrameSink& sink);
    denoise::FrameSource& source() { return m_linear_source ? *m_linear_source : m_source; }
    denoise::FrameSink& sink() { return m_delinear_sink ? *m_delinear_sink : m_sink; }

private:
    denoise::FrameSource& m_source;
    denoise::FrameSink& m_sink;
    std::optional<LinearizingSource> m_linear_source;
    std::optional<DelinearizingSink> m_delinear_sink;
};

} // namespace modestack::app
