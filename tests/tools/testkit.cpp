#include "tests/tools/testkit.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <sys/wait.h>

namespace modestack::testkit {
namespace stdfs = std::filesystem;

TempDir::TempDir()
{
    std::string pattern = (stdfs::temp_directory_path() / "modestack-test-XXXXXX").string();
    if (!mkdtemp(pattern.data()))
        throw std::runtime_error("mkdtemp failed");
    m_path = pattern;
}

TempDir::~TempDir()
{
    std::error_code ignored;
    stdfs::remove_all(m_path, ignored);
}

void write_exr(const std::string& path, const ExrLayout& layout, int frame, const PixelFunction& value)
{
    int channels = static_cast<int>(layout.channel_names.size());
    OIIO::ImageSpec spec(layout.width, layout.height, channels, OIIO::TypeHalf);
    spec.channelnames = layout.channel_names;
    spec.channelformats.clear();
    for (int c = 0; c < channels; ++c)
        spec.channelformats.push_back(
            OIIO::TypeDesc(layout.channel_types.empty() ? "half" : layout.channel_types[c].c_str()));
    spec.alpha_channel = -1;
    if (layout.tile_size > 0)
        spec.tile_width = spec.tile_height = layout.tile_size;
    spec.attribute("compression", layout.compression);
    for (const auto& [name, text] : layout.attributes)
        spec.attribute(name, text);
    std::vector<float> pixels(static_cast<size_t>(layout.width) * layout.height * channels);
    for (int y = 0; y < layout.height; ++y)
        for (int x = 0; x < layout.width; ++x)
            for (int c = 0; c < channels; ++c)
                pixels[(static_cast<size_t>(y) * layout.width + x) * channels + c] = value(frame, x, y, c);
    auto output = OIIO::ImageOutput::create(path);
    if (!output || !output->open(path, spec) || !output->write_image(OIIO::TypeFloat, pixels.data()) ||
        !output->close())
        throw std::runtime_error("cannot write test image " + path);
}

std::vector<std::string> write_sequence(const std::string& printf_pattern, const std::vector<int>& frames,
                                        const ExrLayout& layout, const PixelFunction& value)
{
    std::vector<std::string> files;
    for (int frame : frames) {
        char name[4096];
        std::snprintf(name, sizeof name, printf_pattern.c_str(), frame);
        write_exr(name, layout, frame, value);
        files.push_back(name);
    }
    return files;
}

std::vector<float> read_channels(const std::string& path, const std::vector<std::string>& channels)
{
    auto input = OIIO::ImageInput::open(path);
    if (!input)
        throw std::runtime_error("cannot open " + path);
    const OIIO::ImageSpec& spec = input->spec();
    std::vector<float> all(static_cast<size_t>(spec.width) * spec.height * spec.nchannels);
    if (!input->read_image(0, 0, 0, spec.nchannels, OIIO::TypeFloat, all.data()))
        throw std::runtime_error("cannot read " + path);
    std::vector<float> picked;
    size_t pixels = static_cast<size_t>(spec.width) * spec.height;
    std::vector<int> indices;
    for (const auto& name : channels) {
        int index = spec.channelindex(name);
        if (index < 0)
            throw std::runtime_error("no channel " + name + " in " + path);
        indices.push_back(index);
    }
    for (size_t p = 0; p < pixels; ++p)
        for (int index : indices)
            picked.push_back(all[p * spec.nchannels + index]);
    return picked;
}

std::vector<unsigned char> read_native(const std::string& path)
{
    auto input = OIIO::ImageInput::open(path);
    if (!input)
        throw std::runtime_error("cannot open " + path);
    const OIIO::ImageSpec& spec = input->spec();
    std::vector<unsigned char> bytes(spec.image_bytes(true));
    if (!input->read_image(0, 0, 0, spec.nchannels, OIIO::TypeUnknown, bytes.data()))
        throw std::runtime_error("cannot read " + path);
    return bytes;
}

std::string read_string_attribute(const std::string& path, const std::string& name)
{
    auto input = OIIO::ImageInput::open(path);
    if (!input)
        throw std::runtime_error("cannot open " + path);
    return input->spec().get_string_attribute(name);
}

std::vector<std::string> read_channel_names(const std::string& path)
{
    auto input = OIIO::ImageInput::open(path);
    if (!input)
        throw std::runtime_error("cannot open " + path);
    return input->spec().channelnames;
}

CliResult run_modestack(const std::string& arguments) { return run_modestack_under("", arguments); }

CliResult run_modestack_under(const std::string& launcher, const std::string& arguments)
{
    TempDir capture;
    std::string command = fmt::format("{} {} {} >{} 2>{} </dev/null", launcher, MODESTACK_BINARY, arguments,
                                      capture.file("out"), capture.file("err"));
    int status = std::system(command.c_str());
    CliResult result;
    result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    result.out = read_text(capture.file("out"));
    result.err = read_text(capture.file("err"));
    return result;
}

void report_skipped(const std::string& reason)
{
    std::printf("%s %s\n", kSkippedMarker, reason.c_str());
    std::fflush(stdout);
}

std::string read_text(const std::string& path)
{
    std::ifstream file(path);
    std::stringstream text;
    text << file.rdbuf();
    return text.str();
}

std::vector<std::string> list_directory(const std::string& path)
{
    std::vector<std::string> names;
    for (const auto& entry : stdfs::directory_iterator(path))
        names.push_back(entry.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

}  // namespace modestack::testkit
