#include "io/color_management.h"

#include "core/common/error.h"
#include "io/detail/open_frame.h"
#include "io/sequence_reader.h"

#include <OpenColorIO/OpenColorIO.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <strings.h>

namespace OCIO = OCIO_NAMESPACE;

namespace modestack::io {

struct ColorConfig::Impl {
    OCIO::ConstConfigRcPtr config;
    ColorConfigLocation location;
};

struct ColorConverter::Impl {
    OCIO::ConstCPUProcessorRcPtr to_linear;
    OCIO::ConstCPUProcessorRcPtr from_linear;
    bool identity = false;
};

struct DisplayConverter::Impl {
    OCIO::ConstCPUProcessorRcPtr processor;
    float scale = 1.0f;
};

namespace {

std::string join(const std::vector<std::string>& names)
{
    return fmt::format("{}", fmt::join(names, ", "));
}

// A processor whose output is exact up to float rounding: no LUT or fast-power
// approximations, so that linearizing and back returns the input's values.
OCIO::ConstCPUProcessorRcPtr exact_cpu_processor(const OCIO::ConstProcessorRcPtr& processor)
{
    return processor->getOptimizedCPUProcessor(OCIO::BIT_DEPTH_F32, OCIO::BIT_DEPTH_F32,
                                               OCIO::OPTIMIZATION_LOSSLESS);
}

void apply(const OCIO::ConstCPUProcessorRcPtr& processor, float* pixels, std::size_t pixel_count,
           int channels)
{
    if (channels != 3 && channels != 4)
        throw internal_error(
            fmt::format("colour conversion of {} channels per pixel (3 or 4 expected)", channels));
    if (pixel_count == 0)
        return;
    OCIO::PackedImageDesc image(pixels, static_cast<long>(pixel_count), 1, channels);
    processor->apply(image);
}

bool is_directory_or_missing(const std::string& path)
{
    std::error_code error;
    return !std::filesystem::is_regular_file(path, error);
}

// Primaries and white point (x, y) as EXR's chromaticities attribute orders them.
struct Chromaticities {
    const char* primaries;
    float xy[8];
    std::vector<std::string> candidate_spaces; ///< names in common configs, most specific first
};

const std::vector<Chromaticities>& known_chromaticities()
{
    static const std::vector<Chromaticities> kKnown{
        {"Rec.709",
         {0.64f, 0.33f, 0.30f, 0.60f, 0.15f, 0.06f, 0.3127f, 0.3290f},
         {"lin_rec709", "Linear Rec.709 (sRGB)", "Utility - Linear - Rec.709", "Utility - Linear - sRGB"}},
        {"ACES AP1",
         {0.713f, 0.293f, 0.165f, 0.830f, 0.128f, 0.044f, 0.32168f, 0.33767f},
         {"ACEScg", "ACES - ACEScg", "lin_ap1"}},
        {"ACES AP0",
         {0.7347f, 0.2653f, 0.0f, 1.0f, 0.0001f, -0.0770f, 0.32168f, 0.33767f},
         {"ACES2065-1", "ACES - ACES2065-1", "lin_ap0"}},
    };
    return kKnown;
}

} // namespace

const char* describe(ColorConfigSource source)
{
    switch (source) {
    case ColorConfigSource::CommandLine:
        return "--ocio-config";
    case ColorConfigSource::Environment:
        return "$OCIO";
    case ColorConfigSource::Shipped:
        break;
    }
    return "shipped";
}

std::string shipped_color_config_path()
{
    std::vector<std::filesystem::path> candidates;
    std::error_code error;
    std::filesystem::path binary = std::filesystem::read_symlink("/proc/self/exe", error);
    if (!error)
        candidates.push_back(binary.parent_path() / MODESTACK_OCIO_DIR_FROM_BINARY / "config.ocio");
    candidates.push_back(std::filesystem::path(MODESTACK_SOURCE_OCIO_DIR) / "config.ocio");
    for (const auto& candidate : candidates)
        if (std::filesystem::is_regular_file(candidate, error))
            return candidate.lexically_normal().string();
    return {};
}

ColorConfigLocation locate_color_config(const std::string& command_line_path)
{
    if (!command_line_path.empty())
        return {command_line_path, ColorConfigSource::CommandLine};
    if (const char* environment = std::getenv("OCIO"); environment && *environment)
        return {environment, ColorConfigSource::Environment};
    std::string shipped = shipped_color_config_path();
    if (shipped.empty())
        throw bad_input(
            MODESTACK_OCIO_DIR_FROM_BINARY "/config.ocio",
            "modestack's OpenColorIO config is not installed next to the binary; set $OCIO or give "
            "--ocio-config FILE");
    return {shipped, ColorConfigSource::Shipped};
}

ColorConfig::ColorConfig(const ColorConfigLocation& location)
{
    auto impl = std::make_shared<Impl>();
    impl->location = location;
    const std::string chosen_by = fmt::format("(the OpenColorIO config from {})", describe(location.source));
    if (is_directory_or_missing(location.path))
        throw bad_input(location.path, fmt::format("no such file {}", chosen_by));
    try {
        impl->config = OCIO::Config::CreateFromFile(location.path.c_str());
        impl->config->validate();
    } catch (const OCIO::Exception& exception) {
        throw bad_input(location.path,
                        fmt::format("not a usable OpenColorIO config {}: {}", chosen_by, exception.what()));
    }
    m_impl = std::move(impl);
}

const std::string& ColorConfig::path() const
{
    return m_impl->location.path;
}
ColorConfigSource ColorConfig::source() const
{
    return m_impl->location.source;
}
std::string ColorConfig::name() const
{
    return m_impl->config->getName();
}

std::vector<std::string> ColorConfig::color_space_names() const
{
    std::vector<std::string> names;
    for (int i = 0; i < m_impl->config->getNumColorSpaces(); ++i)
        names.emplace_back(m_impl->config->getColorSpaceNameByIndex(i));
    return names;
}

bool ColorConfig::knows_color_space(const std::string& name) const
{
    return !name.empty() && m_impl->config->getColorSpace(name.c_str()) != nullptr;
}

std::string ColorConfig::find_color_space(const std::string& name, const std::string& option) const
{
    if (!knows_color_space(name))
        throw usage_error(fmt::format("{} '{}': no such colour space in {} (available: {})", option, name,
                                      path(), join(color_space_names())));
    return m_impl->config->getColorSpace(name.c_str())->getName();
}

std::string ColorConfig::scene_linear_space() const
{
    auto space = m_impl->config->getColorSpace(OCIO::ROLE_SCENE_LINEAR);
    if (!space)
        throw bad_input(path(), "the OpenColorIO config has no scene_linear role, which denoising works in");
    return space->getName();
}

bool ColorConfig::is_scene_linear(const std::string& space) const
{
    auto found = m_impl->config->getColorSpace(space.c_str());
    if (!found)
        return false;
    return found->isData() || std::string(found->getName()) == scene_linear_space() ||
           std::string(found->getEncoding()) == "scene-linear";
}

std::vector<std::string> ColorConfig::displays() const
{
    std::vector<std::string> names;
    for (int i = 0; i < m_impl->config->getNumDisplays(); ++i)
        names.emplace_back(m_impl->config->getDisplay(i));
    return names;
}

std::string ColorConfig::default_display() const
{
    return m_impl->config->getDefaultDisplay();
}

std::vector<std::string> ColorConfig::views(const std::string& display) const
{
    std::vector<std::string> names;
    for (int i = 0; i < m_impl->config->getNumViews(display.c_str()); ++i)
        names.emplace_back(m_impl->config->getView(display.c_str(), i));
    return names;
}

std::string ColorConfig::default_view(const std::string& display) const
{
    return m_impl->config->getDefaultView(display.c_str());
}

ColorConverter::ColorConverter(const ColorConfig& config, const std::string& space)
{
    const std::string found = config.find_color_space(space, "colour space");
    const OCIO::ConstConfigRcPtr& ocio = config.impl().config;
    auto impl = std::make_shared<Impl>();
    try {
        OCIO::ConstProcessorRcPtr forward = ocio->getProcessor(found.c_str(), OCIO::ROLE_SCENE_LINEAR);
        OCIO::ConstProcessorRcPtr inverse = ocio->getProcessor(OCIO::ROLE_SCENE_LINEAR, found.c_str());
        impl->to_linear = exact_cpu_processor(forward);
        impl->from_linear = exact_cpu_processor(inverse);
        impl->identity = forward->isNoOp() && inverse->isNoOp();
    } catch (const OCIO::Exception& exception) {
        throw bad_input(config.path(), fmt::format("cannot convert '{}' to and from scene_linear: {}",
                                                   found, exception.what()));
    }
    m_impl = std::move(impl);
}

bool ColorConverter::is_identity() const
{
    return m_impl->identity;
}

void ColorConverter::to_scene_linear(float* pixels, std::size_t pixel_count, int channels) const
{
    apply(m_impl->to_linear, pixels, pixel_count, channels);
}

void ColorConverter::from_scene_linear(float* pixels, std::size_t pixel_count, int channels) const
{
    apply(m_impl->from_linear, pixels, pixel_count, channels);
}

DisplayConverter::DisplayConverter(const ColorConfig& config, const std::string& display,
                                   const std::string& view, double exposure_stops)
    : m_display(display.empty() ? config.default_display() : display), m_exposure_stops(exposure_stops),
      m_config_path(config.path())
{
    std::vector<std::string> displays = config.displays();
    if (std::find(displays.begin(), displays.end(), m_display) == displays.end())
        throw usage_error(fmt::format("--display '{}': no such display in {} (available: {})", m_display,
                                      config.path(), join(displays)));
    m_view = view.empty() ? config.default_view(m_display) : view;
    std::vector<std::string> views = config.views(m_display);
    if (std::find(views.begin(), views.end(), m_view) == views.end())
        throw usage_error(fmt::format("--view '{}': display '{}' of {} has no such view (available: {})",
                                      m_view, m_display, config.path(), join(views)));
    const OCIO::ConstConfigRcPtr& ocio = config.impl().config;
    auto impl = std::make_shared<Impl>();
    impl->scale = static_cast<float>(std::exp2(exposure_stops));
    try {
        OCIO::DisplayViewTransformRcPtr transform = OCIO::DisplayViewTransform::Create();
        transform->setSrc(OCIO::ROLE_SCENE_LINEAR);
        transform->setDisplay(m_display.c_str());
        transform->setView(m_view.c_str());
        impl->processor = ocio->getProcessor(transform)->getDefaultCPUProcessor();
    } catch (const OCIO::Exception& exception) {
        throw bad_input(config.path(), fmt::format("cannot build the display transform '{}' / '{}': {}",
                                                   m_display, m_view, exception.what()));
    }
    m_encoded_color_space = ocio->getDisplayViewColorSpaceName(m_display.c_str(), m_view.c_str());
    auto srgb = ocio->getColorSpace("sRGB");
    auto encoded = ocio->getColorSpace(m_encoded_color_space.c_str());
    if (srgb && encoded && std::string(srgb->getName()) == encoded->getName())
        m_encoded_color_space = "sRGB";
    m_impl = std::move(impl);
}

void DisplayConverter::apply(float* pixels, std::size_t pixel_count, int channels) const
{
    if (m_impl->scale != 1.0f)
        for (std::size_t p = 0; p < pixel_count; ++p)
            for (int c = 0; c < std::min(channels, 3); ++c)
                pixels[p * channels + c] *= m_impl->scale;
    io::apply(m_impl->processor, pixels, pixel_count, channels);
}

RecordedColorSpace recorded_color_space(const SequenceReader& reader, const ColorConfig& config)
{
    const detail::OpenFrame& frame = reader.frame(0);
    std::string named = frame.spec.get_string_attribute("oiio:ColorSpace");
    // OpenImageIO reports a generic linear name for every EXR, whatever it
    // holds ("Linear" in 2.4, "lin_rec709" and the like in later versions).
    static const char* const kGenericLinear[] = {"Linear", "scene_linear", "lin_srgb", "lin_rec709",
                                                 "lin_rec709_scene"};
    bool generic = std::any_of(std::begin(kGenericLinear), std::end(kGenericLinear),
                               [&](const char* name) { return strcasecmp(named.c_str(), name) == 0; });
    if (!named.empty() && !generic) {
        if (!config.knows_color_space(named))
            throw bad_input(frame.file,
                            fmt::format("records colour space '{}' (oiio:ColorSpace), which {} does "
                                        "not know: give --colorspace (available: {})",
                                        named, config.path(), join(config.color_space_names())));
        return {config.find_color_space(named, "oiio:ColorSpace"), "oiio:ColorSpace"};
    }
    const OIIO::ParamValue* attribute = frame.spec.find_attribute("chromaticities");
    if (attribute && attribute->type().basetype == OIIO::TypeDesc::FLOAT &&
        attribute->type().basevalues() == 8) {
        const float* xy = static_cast<const float*>(attribute->data());
        for (const Chromaticities& known : known_chromaticities()) {
            bool same = true;
            for (int i = 0; i < 8; ++i)
                same = same && std::fabs(xy[i] - known.xy[i]) < 1e-3f;
            if (!same)
                continue;
            for (const std::string& candidate : known.candidate_spaces)
                if (config.knows_color_space(candidate))
                    return {config.find_color_space(candidate, "chromaticities"), "chromaticities"};
            throw bad_input(frame.file,
                            fmt::format("records {} chromaticities, for which {} has no colour space "
                                        "({}): give --colorspace",
                                        known.primaries, config.path(), join(known.candidate_spaces)));
        }
        throw bad_input(
            frame.file,
            fmt::format("records chromaticities ({:.4f}) that are not Rec.709, ACES AP1 or AP0: give "
                        "--colorspace (available: {})",
                        fmt::join(xy, xy + 8, ", "), join(config.color_space_names())));
    }
    return {config.scene_linear_space(), "OpenEXR default"};
}

} // namespace modestack::io
