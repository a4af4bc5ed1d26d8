// `modestack info SEQ`: what a sequence holds, like exrheader for a whole shot:
// the frames found (range, count, gaps), data and display windows, channels
// grouped by layer with pixel types, compression and header attributes, and
// which frames disagree with the first. `--json FILE` writes the same facts.
#include "app/command.h"
#include "io/frame_header.h"
#include "io/layers.h"
#include "io/sequence.h"
#include "io/text_output.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <map>

namespace modestack::app {
namespace {

struct InfoOptions {
    std::string pattern;
    std::string frames;
    std::string json_path;
    bool all_attributes = false;
};

// Channels of a layer that share one pixel type, e.g. "R,G,B half".
std::string describe_layer_types(const io::ChannelLayer& layer, const io::FrameHeader& header)
{
    std::vector<std::string> parts;
    size_t i = 0;
    while (i < layer.channel_indices.size()) {
        const std::string& type = header.channel_types[layer.channel_indices[i]];
        std::vector<std::string> components;
        while (i < layer.channel_indices.size() && header.channel_types[layer.channel_indices[i]] == type)
            components.push_back(layer.components[i++]);
        parts.push_back(fmt::format("{} {}", fmt::join(components, ","), type));
    }
    return fmt::format("{}", fmt::join(parts, "; "));
}

bool same_layout(const io::FrameHeader& a, const io::FrameHeader& b)
{
    return a.x == b.x && a.y == b.y && a.width == b.width && a.height == b.height &&
           a.channel_names == b.channel_names && a.channel_types == b.channel_types;
}

int run_info(const InfoOptions& options)
{
    io::FrameSequence sequence = options.frames.empty() ? io::scan_input_sequence(options.pattern)
                                                        : io::find_input_sequence(options.pattern, options.frames);
    std::vector<io::FrameHeader> headers;
    for (const std::string& file : sequence.files)
        headers.push_back(io::read_frame_header(file));
    const io::FrameHeader& first = headers.front();
    std::vector<int> gaps = io::missing_frames(sequence.frames);
    std::vector<int> differing;
    for (size_t i = 1; i < headers.size(); ++i)
        if (!same_layout(headers[i], first))
            differing.push_back(sequence.frames[i]);
    std::vector<io::ChannelLayer> layers = io::group_layers(first.channel_names);

    std::printf("sequence     %s\n", sequence.printf_pattern.c_str());
    std::printf("frames       %s (%zu frames, first %d, last %d)\n", io::describe_frames(sequence.frames).c_str(),
                sequence.frames.size(), sequence.frames.front(), sequence.frames.back());
    std::printf("gaps         %s\n", gaps.empty() ? "none" : io::describe_frames(gaps).c_str());
    std::printf("format       %s%s%s\n", first.format_name.c_str(),
                first.subimages > 1 ? fmt::format(", {} parts", first.subimages).c_str() : "",
                first.deep ? ", deep" : "");
    std::printf("data window  %s\n", io::describe_window(first.x, first.y, first.width, first.height).c_str());
    std::printf("display      %s\n",
                io::describe_window(first.full_x, first.full_y, first.full_width, first.full_height).c_str());
    std::printf("storage      %s, compression %s\n",
                first.tile_width ? fmt::format("tiled {}x{}", first.tile_width, first.tile_height).c_str()
                                 : "scanline",
                first.compression.c_str());
    std::printf("channels     %zu in %zu layers\n", first.channel_names.size(), layers.size());
    for (const auto& layer : layers)
        std::printf("  %-28s %s\n", layer.name.empty() ? "(default)" : layer.name.c_str(),
                    describe_layer_types(layer, first).c_str());
    std::printf("attributes   %zu\n", first.attributes.size());
    for (const auto& [name, value] : first.attributes) {
        std::string shown = value;
        if (!options.all_attributes && shown.size() > 72)
            shown = shown.substr(0, 69) + "...";
        std::printf("  %-28s %s\n", name.c_str(), shown.c_str());
    }
    if (!differing.empty())
        std::printf("mismatch     frames %s differ from frame %d in window or channels\n",
                    io::describe_frames(differing).c_str(), sequence.frames.front());

    if (!options.json_path.empty()) {
        nlohmann::ordered_json json;
        json["sequence"] = sequence.printf_pattern;
        json["frames"] = sequence.frames;
        json["frame_range"] = io::describe_frames(sequence.frames);
        json["frame_count"] = sequence.frames.size();
        json["gaps"] = gaps;
        json["files"] = sequence.files;
        json["format"] = first.format_name;
        json["parts"] = first.subimages;
        json["deep"] = first.deep;
        json["data_window"] = {{"x", first.x}, {"y", first.y}, {"width", first.width}, {"height", first.height}};
        json["display_window"] = {{"x", first.full_x},
                                  {"y", first.full_y},
                                  {"width", first.full_width},
                                  {"height", first.full_height}};
        json["tile_size"] = {first.tile_width, first.tile_height};
        json["compression"] = first.compression;
        nlohmann::ordered_json json_layers = nlohmann::ordered_json::array();
        for (const auto& layer : layers) {
            nlohmann::ordered_json channels = nlohmann::ordered_json::array();
            for (size_t i = 0; i < layer.channel_indices.size(); ++i)
                channels.push_back({{"name", first.channel_names[layer.channel_indices[i]]},
                                    {"component", layer.components[i]},
                                    {"type", first.channel_types[layer.channel_indices[i]]}});
            json_layers.push_back({{"layer", layer.name}, {"channels", channels}});
        }
        json["layers"] = json_layers;
        nlohmann::ordered_json attributes = nlohmann::ordered_json::object();
        for (const auto& [name, value] : first.attributes)
            attributes[name] = value;
        json["attributes"] = attributes;
        json["mismatched_frames"] = differing;
        io::write_text_file(options.json_path, json.dump(2) + "\n");
    }
    return 0;
}

}  // namespace

Subcommand add_info_command(CLI::App& parent)
{
    auto options = std::make_shared<InfoOptions>();
    CLI::App* command = parent.add_subcommand(
        "info", "Describe a frame sequence: frames and gaps, windows, channels by layer, pixel types, attributes");
    command->add_option("SEQ", options->pattern, "Frame-sequence pattern: name.####.exr, name.%04d.exr, name.%d.exr (unpadded), name.@.exr")
        ->required();
    command->add_option("--frames", options->frames, "Only these frames: 1-48, 1001-1100, 1-100x2, 1,3,7-9");
    command->add_option("--json", options->json_path, "Also write the description as JSON to this file");
    command->add_flag("--all-attributes", options->all_attributes, "Print long attribute values in full");
    return {command, [options] { return run_info(*options); }};
}

}  // namespace modestack::app
