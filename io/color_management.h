// Colour management with OpenColorIO, the one place modestack talks to OCIO.
// It decides which config is in use (--ocio-config, else $OCIO, else the small
// config shipped with modestack), checks colour-space, display and view names
// against it with errors that list what is available, finds the colour space an
// input sequence is recorded in, and converts float RGB(A) pixels in place:
// between an input space and the config's scene_linear role (the denoiser's
// working space, both ways, exactly up to float rounding) and from scene-linear
// to a display/view for images people look at. OCIO types never leave this
// file's .cpp, so callers (and core/) need no OCIO headers.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace modestack::io {

class SequenceReader;

/// Who chose the config in use, in order of precedence (oiiotool's: an
/// explicit --colorconfig wins over $OCIO).
enum class ColorConfigSource {
    CommandLine, ///< --ocio-config FILE
    Environment, ///< $OCIO
    Shipped,     ///< modestack's own share/modestack/ocio/config.ocio
};

/// "--ocio-config", "$OCIO" or "shipped".
const char* describe(ColorConfigSource source);

/// A config file and who chose it.
struct ColorConfigLocation {
    std::string path;
    ColorConfigSource source = ColorConfigSource::Shipped;
};

/// The config to use: `command_line_path` when not empty, else $OCIO when set
/// and not empty, else shipped_color_config_path(). Throws Error (bad input)
/// when it falls through to the shipped config and that is missing.
ColorConfigLocation locate_color_config(const std::string& command_line_path);

/// The config shipped with modestack: <binary>/../share/modestack/ocio/config.ocio
/// when installed, else the source tree's share/ocio/config.ocio (build tree).
/// "" when neither exists.
std::string shipped_color_config_path();

/// A loaded, validated OCIO config. Immutable; copies share it.
class ColorConfig {
public:
    /// Loads and validates the config at `location`. Throws Error (bad input)
    /// naming the file and who chose it when it is missing or broken.
    explicit ColorConfig(const ColorConfigLocation& location);

    const std::string& path() const;
    ColorConfigSource source() const;
    /// The config's `name:` field ("" when it has none).
    std::string name() const;
    /// Every colour space of the config, in its order.
    std::vector<std::string> color_space_names() const;
    /// Whether `name` is a colour space, an alias of one or a role.
    bool knows_color_space(const std::string& name) const;
    /// The canonical name of the colour space `name` (a name, alias or role).
    /// Throws a usage error naming `option` and listing the colour spaces when
    /// the config does not know it.
    std::string find_color_space(const std::string& name, const std::string& option) const;
    /// The colour space of the scene_linear role, the denoiser's working space.
    /// Throws Error (bad input) when the config has no such role.
    std::string scene_linear_space() const;
    /// Whether pixels in `space` can be denoised as they are: it is the
    /// scene_linear space, is marked `encoding: scene-linear`, or is data.
    bool is_scene_linear(const std::string& space) const;
    /// The displays of the config and its default.
    std::vector<std::string> displays() const;
    std::string default_display() const;
    /// The views of `display` and its default.
    std::vector<std::string> views(const std::string& display) const;
    std::string default_view(const std::string& display) const;

    struct Impl;

private:
    friend class ColorConverter;
    friend class DisplayConverter;
    const Impl& impl() const { return *m_impl; }
    std::shared_ptr<const Impl> m_impl;
};

/// Converts pixels between one colour space and the config's scene_linear
/// space with OCIO CPU processors. Thread-safe: convert from any thread.
class ColorConverter {
public:
    /// `space` must be known to `config` (see ColorConfig::find_color_space).
    ColorConverter(const ColorConfig& config, const std::string& space);

    /// Whether both directions leave every value unchanged.
    bool is_identity() const;
    /// Converts `pixel_count` interleaved pixels of `channels` floats (3 = RGB,
    /// 4 = RGBA, alpha untouched) in place from `space` to scene-linear.
    void to_scene_linear(float* pixels, std::size_t pixel_count, int channels = 3) const;
    /// The inverse of to_scene_linear.
    void from_scene_linear(float* pixels, std::size_t pixel_count, int channels = 3) const;

    struct Impl;

private:
    std::shared_ptr<const Impl> m_impl;
};

/// Turns scene-linear pixels into display-encoded values for a display and
/// view of the config (as OCIO's DisplayViewTransform), after an exposure in
/// stops. Thread-safe.
class DisplayConverter {
public:
    /// `display` and `view` "" = the config's defaults. Throws a usage error
    /// listing the displays (or the display's views) when one is unknown.
    DisplayConverter(const ColorConfig& config, const std::string& display, const std::string& view,
                     double exposure_stops = 0.0);

    const std::string& display() const { return m_display; }
    const std::string& view() const { return m_view; }
    double exposure_stops() const { return m_exposure_stops; }
    /// The config file the transform comes from.
    const std::string& config_path() const { return m_config_path; }
    /// The colour space the display/view encodes to; "sRGB" when that is the
    /// config's sRGB space, so that image files can say so (PNG's sRGB chunk).
    const std::string& encoded_color_space() const { return m_encoded_color_space; }
    /// Converts interleaved scene-linear RGB(A) pixels in place to display
    /// values (nominally [0, 1]; not clipped here).
    void apply(float* pixels, std::size_t pixel_count, int channels = 3) const;

    struct Impl;

private:
    std::string m_display;
    std::string m_view;
    double m_exposure_stops = 0.0;
    std::string m_config_path;
    std::string m_encoded_color_space;
    std::shared_ptr<const Impl> m_impl;
};

/// The colour space an input sequence's pixels are in, and how we know.
struct RecordedColorSpace {
    std::string space;    ///< canonical name in the config
    std::string evidence; ///< "oiio:ColorSpace", "chromaticities" or "OpenEXR default"
};

/// Reads the colour space the first frame of `reader` records: a specific
/// oiio:ColorSpace (OpenImageIO reports a generic "Linear" for every EXR,
/// which says nothing), else the EXR chromaticities when they are Rec.709,
/// ACES AP1 or AP0 primaries and the config has such a space, else scene-linear
/// (OpenEXR's convention). Throws Error (bad input) naming the file when it
/// records a space the config does not know: give --colorspace.
RecordedColorSpace recorded_color_space(const SequenceReader& reader, const ColorConfig& config);

} // namespace modestack::io
