// The text and JSON of `modestack info`: the frames found and how they were
// checked, then the header of the first readable frame: windows, storage, the
// channels grouped by layer with their pixel types (for every part of a
// multi-part file), attributes, and the frames whose layout differs from it.
#include "app/info_description.h"

#include "io/layers.h"

#include <fmt/format.h>

#include <cstdio>

namespace modestack::app {
namespace {

// Channels of a layer that share one pixel type, e.g. "R,G,B half".
std::string describe_layer_types(const io::ChannelLayer& layer, const io::ImagePart& part)
{
    std::vector<std::string> runs;
    size_t i = 0;
    while (i < layer.channel_indices.size()) {
        const std::string& type = part.channel_types[layer.channel_indices[i]];
        std::vector<std::string> components;
        while (i < layer.channel_indices.size() && part.channel_types[layer.channel_indices[i]] == type)
            components.push_back(layer.components[i++]);
        runs.push_back(fmt::format("{} {}", fmt::join(components, ","), type));
    }
    return fmt::format("{}", fmt::join(runs, "; "));
}

std::string describe_storage(const io::ImagePart& part)
{
    return part.tile_width ? fmt::format("tiled {}x{}", part.tile_width, part.tile_height) : "scanline";
}

bool same_part_layout(const io::ImagePart& a, const io::ImagePart& b)
{
    return a.x == b.x && a.y == b.y && a.width == b.width && a.height == b.height &&
           a.channel_names == b.channel_names && a.channel_types == b.channel_types;
}

// The window and channels of every part: what every frame must share with the reference.
bool same_layout(const io::FrameHeader& a, const io::FrameHeader& b)
{
    if (a.parts.size() != b.parts.size())
        return false;
    for (size_t p = 0; p < a.parts.size(); ++p)
        if (!same_part_layout(a.parts[p], b.parts[p]))
            return false;
    return true;
}

std::vector<int> differing_frames(const InfoFindings& findings, const io::FrameHeader& reference)
{
    std::vector<int> differing;
    for (const CheckedFrame& frame : findings.frames)
        if (frame.header && !same_layout(*frame.header, reference))
            differing.push_back(frame.frame);
    return differing;
}

const char* depth_name(FrameCheckDepth depth)
{
    return depth == FrameCheckDepth::EveryChunk ? "every chunk decoded" : "chunk tables against file sizes";
}

void print_layers(const io::ImagePart& part, const char* indent, int name_width)
{
    for (const auto& layer : io::group_layers(part.channel_names))
        std::printf("%s%-*s %s\n", indent, name_width, layer.name.empty() ? "(default)" : layer.name.c_str(),
                    describe_layer_types(layer, part).c_str());
}

void print_channels(const io::FrameHeader& header)
{
    if (header.parts.size() <= 1) {
        std::printf("channels     %zu in %zu layers\n", header.channel_names.size(),
                    io::group_layers(header.channel_names).size());
        print_layers(header, "  ", 28);
        return;
    }
    size_t channels = 0;
    for (const io::ImagePart& part : header.parts)
        channels += part.channel_names.size();
    std::printf("channels     %zu in %zu parts\n", channels, header.parts.size());
    for (size_t p = 0; p < header.parts.size(); ++p) {
        const io::ImagePart& part = header.parts[p];
        std::printf("  part %zu %s: %zu channels, %s, %s, compression %s%s\n", p,
                    part.name.empty() ? "(unnamed)" : part.name.c_str(), part.channel_names.size(),
                    io::describe_window(part.x, part.y, part.width, part.height).c_str(),
                    describe_storage(part).c_str(), part.compression.c_str(), part.deep ? ", deep" : "");
        print_layers(part, "    ", 26);
    }
}

nlohmann::ordered_json layers_json(const io::ImagePart& part)
{
    nlohmann::ordered_json layers = nlohmann::ordered_json::array();
    for (const auto& layer : io::group_layers(part.channel_names)) {
        nlohmann::ordered_json channels = nlohmann::ordered_json::array();
        for (size_t i = 0; i < layer.channel_indices.size(); ++i)
            channels.push_back({{"name", part.channel_names[layer.channel_indices[i]]},
                                {"component", layer.components[i]},
                                {"type", part.channel_types[layer.channel_indices[i]]}});
        layers.push_back({{"layer", layer.name}, {"channels", channels}});
    }
    return layers;
}

nlohmann::ordered_json window_json(int x, int y, int width, int height)
{
    return {{"x", x}, {"y", y}, {"width", width}, {"height", height}};
}

} // namespace

void print_info(const InfoFindings& findings, bool all_attributes)
{
    const io::FrameSequence& sequence = findings.sequence;
    const std::vector<int> gaps = io::missing_frames(sequence.frames);
    const std::vector<int> bad = findings.bad_frames();
    std::printf("sequence     %s\n", sequence.printf_pattern.c_str());
    std::printf("frames       %s (%zu frames, first %d, last %d)\n",
                io::describe_frames(sequence.frames).c_str(), sequence.frames.size(), sequence.frames.front(),
                sequence.frames.back());
    std::printf("gaps         %s\n", gaps.empty() ? "none" : io::describe_frames(gaps).c_str());
    if (bad.empty())
        std::printf("check        all %zu frames whole (%s)\n", sequence.frames.size(),
                    depth_name(findings.depth));
    else
        std::printf("check        %zu of %zu frames bad: %s (%s; each is named on stderr)\n", bad.size(),
                    sequence.frames.size(), io::describe_frames(bad).c_str(), depth_name(findings.depth));
    const CheckedFrame* reference = findings.reference();
    if (!reference)
        return;
    const io::FrameHeader& first = *reference->header;
    std::printf("format       %s%s%s\n", first.format_name.c_str(),
                first.parts.size() > 1 ? fmt::format(", {} parts", first.parts.size()).c_str() : "",
                first.deep ? ", deep" : "");
    if (reference->frame != sequence.frames.front())
        std::printf("described    frame %d, the first whose header can be read\n", reference->frame);
    std::printf("data window  %s\n",
                io::describe_window(first.x, first.y, first.width, first.height).c_str());
    std::printf("display      %s\n",
                io::describe_window(first.full_x, first.full_y, first.full_width, first.full_height).c_str());
    std::printf("storage      %s, compression %s\n", describe_storage(first).c_str(),
                first.compression.c_str());
    print_channels(first);
    std::printf("attributes   %zu\n", first.attributes.size());
    for (const auto& [name, value] : first.attributes) {
        std::string shown = value;
        if (!all_attributes && shown.size() > 72)
            shown = shown.substr(0, 69) + "...";
        std::printf("  %-28s %s\n", name.c_str(), shown.c_str());
    }
    const std::vector<int> differing = differing_frames(findings, first);
    if (!differing.empty())
        std::printf("mismatch     frames %s differ from frame %d in window, channels or parts\n",
                    io::describe_frames(differing).c_str(), reference->frame);
}

nlohmann::ordered_json info_json(const InfoFindings& findings)
{
    const io::FrameSequence& sequence = findings.sequence;
    nlohmann::ordered_json json;
    json["sequence"] = sequence.printf_pattern;
    json["frames"] = sequence.frames;
    json["frame_range"] = io::describe_frames(sequence.frames);
    json["frame_count"] = sequence.frames.size();
    json["gaps"] = io::missing_frames(sequence.frames);
    json["files"] = sequence.files;
    json["check"] = findings.depth == FrameCheckDepth::EveryChunk ? "every_chunk" : "chunk_tables";
    json["bad_frames"] = findings.bad_frames();
    nlohmann::ordered_json checks = nlohmann::ordered_json::array();
    for (const CheckedFrame& frame : findings.frames)
        checks.push_back({{"frame", frame.frame},
                          {"file", frame.file},
                          {"ok", frame.problem.empty()},
                          {"problem", frame.problem.empty() ? nlohmann::ordered_json()
                                                            : nlohmann::ordered_json(frame.problem)}});
    json["frame_checks"] = checks;
    const CheckedFrame* reference = findings.reference();
    if (!reference)
        return json;
    const io::FrameHeader& first = *reference->header;
    json["described_frame"] = reference->frame;
    json["format"] = first.format_name;
    json["parts"] = first.parts.size();
    json["deep"] = first.deep;
    json["data_window"] = window_json(first.x, first.y, first.width, first.height);
    json["display_window"] = window_json(first.full_x, first.full_y, first.full_width, first.full_height);
    json["tile_size"] = {first.tile_width, first.tile_height};
    json["compression"] = first.compression;
    json["layers"] = layers_json(first);
    nlohmann::ordered_json parts = nlohmann::ordered_json::array();
    for (size_t p = 0; p < first.parts.size(); ++p) {
        const io::ImagePart& part = first.parts[p];
        parts.push_back({{"part", p},
                         {"name", part.name},
                         {"data_window", window_json(part.x, part.y, part.width, part.height)},
                         {"tile_size", {part.tile_width, part.tile_height}},
                         {"compression", part.compression},
                         {"deep", part.deep},
                         {"layers", layers_json(part)}});
    }
    json["part_list"] = parts;
    nlohmann::ordered_json attributes = nlohmann::ordered_json::object();
    for (const auto& [name, value] : first.attributes)
        attributes[name] = value;
    json["attributes"] = attributes;
    json["mismatched_frames"] = differing_frames(findings, first);
    return json;
}

} // namespace modestack::app
