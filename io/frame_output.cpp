#include "io/frame_output.h"

#include "core/common/error.h"
#include "io/detail/open_frame.h"
#include "io/sequence_reader.h"
#include "io/temporary_file.h"

#include <Imath/half.h>
#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <set>
#include <system_error>
#include <utility>
#include <unistd.h>

namespace modestack::io {
namespace {

namespace stdfs = std::filesystem;

// Stores a float in a channel of the given pixel type.
void store_value(float value, OIIO::TypeDesc type, unsigned char* destination)
{
    if (type == OIIO::TypeDesc::HALF) {
        Imath::half h(value);
        std::memcpy(destination, &h, sizeof h);
    } else if (type == OIIO::TypeDesc::FLOAT) {
        std::memcpy(destination, &value, sizeof value);
    } else {
        OIIO::convert_pixel_values(OIIO::TypeFloat, &value, type, destination, 1);
    }
}

void add_attributes(OIIO::ImageSpec& spec, const std::vector<HeaderAttribute>& attributes)
{
    for (const auto& attribute : attributes) {
        switch (attribute.kind) {
        case HeaderAttribute::Kind::Text: spec.attribute(attribute.name, attribute.text); break;
        case HeaderAttribute::Kind::Integer: spec.attribute(attribute.name, static_cast<int>(attribute.integer)); break;
        case HeaderAttribute::Kind::Real: spec.attribute(attribute.name, static_cast<float>(attribute.real)); break;
        }
    }
}

}  // namespace

HeaderAttribute HeaderAttribute::of_text(std::string name, std::string value)
{
    HeaderAttribute attribute;
    attribute.name = std::move(name);
    attribute.text = std::move(value);
    return attribute;
}
HeaderAttribute HeaderAttribute::of_integer(std::string name, long long value)
{
    HeaderAttribute attribute;
    attribute.name = std::move(name);
    attribute.kind = Kind::Integer;
    attribute.integer = value;
    return attribute;
}
HeaderAttribute HeaderAttribute::of_real(std::string name, double value)
{
    HeaderAttribute attribute;
    attribute.name = std::move(name);
    attribute.kind = Kind::Real;
    attribute.real = value;
    return attribute;
}

struct FrameOutput::State {
    std::unique_ptr<OIIO::ImageOutput> output;
    OIIO::ImageSpec spec;
    const detail::OpenFrame* source = nullptr;  ///< the copied input frame, if any
    std::vector<OIIO::TypeDesc> extra_types;
    size_t output_pixel_bytes = 0;
};

FrameOutput::FrameOutput(const std::string& path, const SequenceReader& reader, int frame_index,
                         const std::vector<std::string>& extra_channels,
                         const std::vector<HeaderAttribute>& attributes)
    : m_path(path), m_state(std::make_unique<State>())
{
    const detail::OpenFrame& source = reader.frame(frame_index);
    m_state->source = &source;
    OIIO::ImageSpec spec = source.spec;
    if (spec.channelformats.empty())
        spec.channelformats.assign(spec.nchannels, spec.format);
    OIIO::TypeDesc extra_type = spec.channelformats[source.selected.front()];
    for (const std::string& name : extra_channels) {
        spec.channelnames.push_back(name);
        spec.channelformats.push_back(extra_type);
        m_state->extra_types.push_back(extra_type);
    }
    spec.nchannels = static_cast<int>(spec.channelnames.size());
    spec.alpha_channel = source.spec.alpha_channel;
    spec.tile_width = spec.tile_height = spec.tile_depth = 0;
    spec.erase_attribute("openexr:lineOrder");
    add_attributes(spec, attributes);
    m_state->output_pixel_bytes = source.native_pixel_bytes + extra_channels.size() * extra_type.size();
    open(&spec);
}

FrameOutput::FrameOutput(const std::string& path, const NewImageDescription& image,
                         const std::vector<HeaderAttribute>& attributes)
    : m_path(path), m_state(std::make_unique<State>())
{
    OIIO::ImageSpec spec(image.width, image.height, static_cast<int>(image.channel_names.size()), OIIO::TypeFloat);
    spec.channelnames = image.channel_names;
    spec.channelformats.clear();
    for (const std::string& type : image.channel_types)
        spec.channelformats.push_back(OIIO::TypeDesc(type));
    spec.alpha_channel = -1;
    for (size_t c = 0; c < image.channel_names.size(); ++c)
        if (image.channel_names[c] == "A" || (image.channel_names[c].size() > 2 &&
                                              image.channel_names[c].compare(image.channel_names[c].size() - 2, 2, ".A") == 0)) {
            spec.alpha_channel = static_cast<int>(c);
            break;
        }
    spec.attribute("compression", image.compression);
    add_attributes(spec, attributes);
    open(&spec);
}

void FrameOutput::open(const void* spec_pointer)
{
    const OIIO::ImageSpec& spec = *static_cast<const OIIO::ImageSpec*>(spec_pointer);
    m_state->spec = spec;
    remove_stale_temporaries(m_path);
    m_temporary_path = temporary_path_for(m_path);
    m_state->output = OIIO::ImageOutput::create("openexr");
    if (!m_state->output)
        throw internal_error("OpenImageIO has no OpenEXR writer");
    errno = 0;  // fail() reports the system's reason, e.g. a full disk
    if (!m_state->output->open(m_temporary_path, m_state->spec))
        fail("cannot create output");
}

FrameOutput::~FrameOutput()
{
    if (m_committed)
        return;
    if (m_state && m_state->output)
        m_state->output->close();
    std::error_code ignored;
    if (!m_temporary_path.empty())
        stdfs::remove(m_temporary_path, ignored);
}

void FrameOutput::fail(const std::string& what)
{
    const int system_error = errno;  // OpenEXR's message ("File output failed.") does not say why
    std::string reason = m_state->output ? m_state->output->geterror() : std::string();
    if (system_error != 0) {
        const std::string system_reason = std::strerror(system_error);
        reason = reason.empty() ? system_reason : fmt::format("{}: {}", reason, system_reason);
    }
    throw bad_input(m_path, reason.empty() ? what : fmt::format("{} ({})", what, reason));
}

void FrameOutput::write_replaced_rows(int row_begin, int row_end, const std::vector<unsigned char>& input_native,
                                      const float* replaced, const float* extra)
{
    const detail::OpenFrame& source = *m_state->source;
    size_t pixels = static_cast<size_t>(source.spec.width) * (row_end - row_begin);
    if (needs_input_rows() && input_native.size() != pixels * source.native_pixel_bytes)
        throw internal_error("native row buffer has the wrong size");
    write_replaced_rows(row_begin, row_end, input_native.empty() ? nullptr : input_native.data(), replaced, extra);
}

void FrameOutput::write_replaced_rows(int row_begin, int row_end, const unsigned char* input_native,
                                      const float* replaced, const float* extra)
{
    const detail::OpenFrame& source = *m_state->source;
    const OIIO::ImageSpec& input_spec = source.spec;
    size_t pixels = static_cast<size_t>(input_spec.width) * (row_end - row_begin);
    size_t in_bytes = source.native_pixel_bytes, out_bytes = m_state->output_pixel_bytes;
    size_t replaced_count = source.selected.size(), extra_count = m_state->extra_types.size();
    // Without pass-through channels every input byte is overwritten: no input rows needed.
    const bool copy_input = needs_input_rows();
    if (copy_input && !input_native)
        throw internal_error("native rows missing for a frame with pass-through channels");
    // Per thread, not per output: a shot has hundreds of outputs open at once.
    thread_local std::vector<unsigned char> scratch;
    scratch.resize(pixels * out_bytes);
    unsigned char* out = scratch.data();
    // Where and as what each written value goes in a pixel, looked up once per call
    // rather than per value (this loop touches every value of every frame).
    thread_local std::vector<std::pair<size_t, OIIO::TypeDesc>> replaced_places, extra_places;
    replaced_places.clear();
    for (size_t k = 0; k < replaced_count; ++k) {
        int channel = source.selected[k];
        replaced_places.emplace_back(source.byte_offset[channel], input_spec.channelformat(channel));
    }
    extra_places.clear();
    for (size_t k = 0, offset = in_bytes; k < extra_count; offset += m_state->extra_types[k].size(), ++k)
        extra_places.emplace_back(offset, m_state->extra_types[k]);
    for (size_t p = 0; p < pixels; ++p) {
        unsigned char* pixel = out + p * out_bytes;
        if (copy_input)
            std::memcpy(pixel, input_native + p * in_bytes, in_bytes);
        for (size_t k = 0; k < replaced_count; ++k)
            store_value(replaced[p * replaced_count + k], replaced_places[k].second, pixel + replaced_places[k].first);
        for (size_t k = 0; k < extra_count; ++k)
            store_value(extra[p * extra_count + k], extra_places[k].second, pixel + extra_places[k].first);
    }
    const OIIO::ImageSpec& spec = m_state->spec;
    errno = 0;  // fail() reports the system's reason, e.g. a full disk
    if (!m_state->output->write_scanlines(spec.y + row_begin, spec.y + row_end, spec.z, OIIO::TypeUnknown, out))
        fail(fmt::format("cannot write rows {}-{}", row_begin, row_end - 1));
}

bool FrameOutput::needs_input_rows() const
{
    const detail::OpenFrame* source = m_state->source;
    return source && static_cast<int>(source->selected.size()) < source->spec.nchannels;
}

void FrameOutput::write_float_rows(int row_begin, int row_end, const float* pixels)
{
    const OIIO::ImageSpec& spec = m_state->spec;
    errno = 0;  // fail() reports the system's reason, e.g. a full disk
    if (!m_state->output->write_scanlines(spec.y + row_begin, spec.y + row_end, spec.z, OIIO::TypeFloat, pixels))
        fail(fmt::format("cannot write rows {}-{}", row_begin, row_end - 1));
}

void FrameOutput::commit()
{
    errno = 0;  // fail() reports the system's reason, e.g. a full disk
    if (!m_state->output->close())
        fail("cannot finish writing");
    m_state->output.reset();
    std::error_code error;
    stdfs::rename(m_temporary_path, m_path, error);
    if (error)
        throw bad_input(m_path, fmt::format("cannot rename the finished file into place ({})", error.message()));
    m_committed = true;
}

void check_outputs(const std::vector<std::string>& outputs, const std::vector<std::string>& inputs)
{
    std::set<std::string> input_paths;
    for (const std::string& input : inputs)
        input_paths.insert(stdfs::weakly_canonical(input).string());
    std::set<std::string> checked_directories;
    for (const std::string& output : outputs) {
        if (input_paths.count(stdfs::weakly_canonical(output).string()))
            throw usage_error(fmt::format("output '{}' is also an input; modestack never overwrites its input", output));
        stdfs::path directory = stdfs::path(output).parent_path();
        if (directory.empty())
            directory = ".";
        if (!checked_directories.insert(directory.string()).second)
            continue;
        std::error_code error;
        if (stdfs::exists(directory, error) && !stdfs::is_directory(directory, error))
            throw bad_input(directory.string(), "output directory is a file");
        stdfs::create_directories(directory, error);
        if (error)
            throw bad_input(directory.string(), fmt::format("cannot create output directory ({})", error.message()));
        if (access(directory.c_str(), W_OK) != 0)
            throw bad_input(directory.string(), "output directory is not writable");
    }
}

}  // namespace modestack::io
