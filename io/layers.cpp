#include "io/layers.h"

#include "core/common/error.h"

#include <fmt/format.h>

#include <algorithm>

namespace modestack::io {
namespace {

bool has_rgb(const ChannelLayer& layer)
{
    auto has = [&](const char* component) {
        return std::find(layer.components.begin(), layer.components.end(), component) != layer.components.end();
    };
    return has("R") && has("G") && has("B");
}

bool layer_matches(const std::string& layer, const std::string& selector)
{
    if (layer == selector)
        return true;
    return layer.size() > selector.size() && layer.compare(layer.size() - selector.size(), selector.size(), selector) == 0 &&
           layer[layer.size() - selector.size() - 1] == '.';
}

SelectedLayer make_selection(const ChannelLayer& layer, const std::vector<std::string>& channel_names)
{
    SelectedLayer selected;
    selected.name = layer.name;
    bool rgb = has_rgb(layer);
    for (size_t i = 0; i < layer.channel_indices.size(); ++i) {
        const std::string& component = layer.components[i];
        // Alpha is coverage, not light: it passes through untouched.
        if (component == "A" || (rgb && component != "R" && component != "G" && component != "B"))
            continue;
        int index = layer.channel_indices[i];
        selected.channel_indices.push_back(index);
        selected.channel_names.push_back(channel_names[index]);
        selected.sigma_names.push_back(layer.name.empty() ? "sigma." + component
                                                          : layer.name + ".sigma." + component);
    }
    return selected;
}

}  // namespace

std::vector<std::string> part_channel_names(const std::string& part_name,
                                            const std::vector<std::string>& channels)
{
    const bool named_within_part =
        !part_name.empty() && std::any_of(channels.begin(), channels.end(), [](const std::string& channel) {
            return channel.find('.') == std::string::npos;
        });
    if (!named_within_part)
        return channels;
    std::vector<std::string> names;
    for (const std::string& channel : channels)
        names.push_back(part_name + "." + channel);
    return names;
}

void split_channel_name(const std::string& channel, std::string& layer, std::string& component)
{
    size_t dot = channel.rfind('.');
    if (dot == std::string::npos) {
        layer.clear();
        component = channel;
    } else {
        layer = channel.substr(0, dot);
        component = channel.substr(dot + 1);
    }
}

std::vector<ChannelLayer> group_layers(const std::vector<std::string>& channel_names)
{
    std::vector<ChannelLayer> layers;
    for (size_t i = 0; i < channel_names.size(); ++i) {
        std::string layer_name, component;
        split_channel_name(channel_names[i], layer_name, component);
        auto found = std::find_if(layers.begin(), layers.end(),
                                  [&](const ChannelLayer& layer) { return layer.name == layer_name; });
        if (found == layers.end()) {
            layers.push_back({layer_name, {}, {}});
            found = layers.end() - 1;
        }
        found->channel_indices.push_back(static_cast<int>(i));
        found->components.push_back(component);
    }
    return layers;
}

std::string describe_layers(const std::vector<ChannelLayer>& layers)
{
    std::vector<std::string> parts;
    for (const auto& layer : layers)
        parts.push_back(fmt::format("{} [{}]", layer.name.empty() ? "(default)" : layer.name,
                                    fmt::join(layer.components, ",")));
    return fmt::format("{}", fmt::join(parts, ", "));
}

std::vector<SelectedLayer> select_layers(const std::vector<std::string>& channel_names,
                                         const std::vector<std::string>& selectors, const std::string& file)
{
    std::vector<ChannelLayer> layers = group_layers(channel_names);
    std::vector<SelectedLayer> selected;
    if (selectors.empty()) {
        std::vector<const ChannelLayer*> rgb_layers;
        for (const auto& layer : layers)
            if (has_rgb(layer))
                rgb_layers.push_back(&layer);
        if (rgb_layers.size() != 1)
            throw bad_input(file, fmt::format("{} RGB layers; choose with --layer (layers: {})",
                                              rgb_layers.empty() ? "no" : "several", describe_layers(layers)));
        selected.push_back(make_selection(*rgb_layers.front(), channel_names));
        return selected;
    }
    for (const std::string& selector : selectors) {
        std::vector<const ChannelLayer*> matches;
        for (const auto& layer : layers)
            if (layer_matches(layer.name, selector))
                matches.push_back(&layer);
        // A bare channel of the unnamed layer (Arnold's Z) is a layer of its own.
        ChannelLayer bare_channel;
        if (matches.empty())
            for (const auto& layer : layers)
                for (size_t i = 0; layer.name.empty() && i < layer.components.size(); ++i)
                    if (layer.components[i] == selector && selector != "R" && selector != "G" &&
                        selector != "B" && selector != "A") {
                        bare_channel = {"", {layer.channel_indices[i]}, {selector}};
                        matches.push_back(&bare_channel);
                    }
        if (matches.empty())
            throw bad_input(file, fmt::format("layer '{}' not found (layers: {})", selector, describe_layers(layers)));
        if (matches.size() > 1) {
            std::vector<std::string> names;
            for (auto* match : matches)
                names.push_back(match->name);
            throw bad_input(file, fmt::format("layer '{}' is ambiguous: {} (give the full name)", selector,
                                              fmt::join(names, ", ")));
        }
        SelectedLayer layer = make_selection(*matches.front(), channel_names);
        if (matches.front() == &bare_channel)
            layer.name = selector;
        if (layer.channel_indices.empty())
            throw bad_input(file, fmt::format("layer '{}' has no channel to denoise", selector));
        for (const auto& previous : selected)
            if (previous.name == layer.name)
                throw usage_error(fmt::format("--layer '{}' is given twice", selector));
        selected.push_back(layer);
    }
    return selected;
}

}  // namespace modestack::io
