// Detection of a shot's renderer and the names of its guide and variance
// layers, from the conventions table (renderer_detection.h).
#include "app/renderer_detection.h"

#include "core/common/error.h"
#include "core/denoise/feature_guide.h"

#include <fmt/format.h>

#include <algorithm>
#include <fnmatch.h>
#include <set>

namespace modestack::app {
namespace {

bool matches(const std::string& pattern, const std::string& text)
{
    return fnmatch(pattern.c_str(), text.c_str(), 0) == 0;
}

// The first header attribute of `header` that a name rule of `renderer` matches
// (`values`: a value rule, weaker evidence, asked only when no renderer's name rule matched), or "".
std::string attribute_evidence(const RendererConvention& renderer, const io::FrameHeader& header, bool values)
{
    for (const auto& [name, typed_value] : header.attributes) {
        if (!values) {
            for (const std::string& pattern : renderer.detect_attributes)
                if (matches(pattern, name))
                    return fmt::format("header attribute {}", name);
            continue;
        }
        const std::string value = io::attribute_value(typed_value);
        for (const AttributeValueRule& rule : renderer.detect_values)
            if (matches(rule.attribute, name) && matches(rule.value, value))
                return fmt::format("header attribute {} = {}", name,
                                   value.size() > 40 ? value.substr(0, 40) + "..." : value);
    }
    return {};
}

// Every layer name of every part, and each one's last dot-part ("DiffCol" of "ViewLayer.DiffCol").
std::set<std::string> layer_names(const io::FrameHeader& header)
{
    std::set<std::string> names;
    auto add = [&](const std::string& layer) {
        if (layer.empty())
            return;
        names.insert(layer);
        if (const size_t dot = layer.rfind('.'); dot != std::string::npos)
            names.insert(layer.substr(dot + 1));
    };
    std::vector<io::ImagePart> parts = header.parts;
    if (parts.empty())
        parts.push_back(header);
    for (const io::ImagePart& part : parts) {
        add(part.name);
        for (const std::string& channel : part.channel_names) {
            std::string layer, component;
            io::split_channel_name(channel, layer, component);
            add(layer);
        }
    }
    return names;
}

// The layer patterns of `renderer` that some layer of the file matches.
std::vector<std::string> layer_evidence(const RendererConvention& renderer,
                                        const std::set<std::string>& layers)
{
    std::vector<std::string> matched;
    for (const std::string& pattern : renderer.detect_layers)
        if (std::any_of(layers.begin(), layers.end(),
                        [&](const std::string& layer) { return matches(pattern, layer); }))
            matched.push_back(pattern);
    return matched;
}

void add_candidate(std::vector<std::vector<std::string>>& candidates, std::vector<std::string> selectors)
{
    if (std::find(candidates.begin(), candidates.end(), selectors) == candidates.end())
        candidates.push_back(std::move(selectors));
}

// The variance names of one denoised layer in `renderer`, best first, full names.
std::vector<std::string> variance_names(const RendererConvention& renderer, const std::string& layer)
{
    const std::string prefix = layer_prefix(layer);
    const std::string short_name = layer.substr(prefix.size());
    std::vector<std::string> names;
    if (auto by_layer = renderer.variance_by_layer.find(short_name);
        by_layer != renderer.variance_by_layer.end())
        for (const std::string& name : by_layer->second)
            names.push_back(prefix + name);
    if (!short_name.empty()) // {layer} of the unnamed R, G, B would name nothing
        for (std::string name : renderer.variance) {
            for (size_t at; (at = name.find("{layer}")) != std::string::npos;)
                name.replace(at, 7, short_name);
            names.push_back(prefix + name);
        }
    return names;
}

} // namespace

std::string layer_prefix(const std::string& layer)
{
    const size_t dot = layer.rfind('.');
    return dot == std::string::npos ? "" : layer.substr(0, dot + 1);
}

void check_renderer_name(const ConventionTable& table, const std::string& requested)
{
    if (requested != "auto" && !table.find(requested))
        throw usage_error(
            fmt::format("--renderer '{}' is not in the renderer conventions ({}): use auto or one of {}",
                        requested, table.source, table.names()));
}

RendererChoice choose_renderer(const ConventionTable& table, const std::string& requested,
                               const io::FrameHeader& header)
{
    check_renderer_name(table, requested);
    RendererChoice choice;
    choice.table = table.source;
    if (requested != "auto") {
        const RendererConvention* renderer = table.find(requested);
        choice.conventions = {renderer};
        choice.name = renderer->name;
        choice.detected_by = fmt::format("--renderer {}", requested);
        return choice;
    }
    for (bool values : {false, true})
        for (const RendererConvention& renderer : table.renderers)
            if (std::string evidence = attribute_evidence(renderer, header, values); !evidence.empty()) {
                choice.conventions = {&renderer};
                choice.name = renderer.name;
                choice.detected_by = std::move(evidence);
                return choice;
            }
    const std::set<std::string> layers = layer_names(header);
    std::vector<std::string> best;
    for (const RendererConvention& renderer : table.renderers)
        if (std::vector<std::string> evidence = layer_evidence(renderer, layers);
            evidence.size() > best.size()) {
            best = std::move(evidence);
            choice.conventions = {&renderer};
            choice.name = renderer.name;
        }
    if (!best.empty()) {
        choice.detected_by = fmt::format("layers {}", fmt::join(best, ", "));
        return choice;
    }
    for (const RendererConvention& renderer : table.renderers)
        choice.conventions.push_back(&renderer);
    choice.name = "unknown";
    choice.detected_by = "no header attribute or layer of a known renderer: every renderer's names are tried";
    return choice;
}

AuxiliaryCandidates auxiliary_candidates(const RendererChoice& choice,
                                         const std::vector<io::SelectedLayer>& layers)
{
    AuxiliaryCandidates candidates;
    if (layers.empty())
        return candidates;
    const std::string prefix = layer_prefix(layers.front().name);
    const denoise::Auxiliary guides[] = {denoise::Auxiliary::Albedo, denoise::Auxiliary::Normal,
                                         denoise::Auxiliary::Depth};
    for (const RendererConvention* renderer : choice.conventions) {
        for (denoise::Auxiliary kind : guides)
            if (auto names = renderer->guides.find(denoise::auxiliary_name(kind));
                names != renderer->guides.end())
                for (const std::string& name : names->second)
                    add_candidate(candidates[static_cast<size_t>(kind)], {prefix + name});
        // A variance per denoised layer: the k-th name of each (its last when it has fewer).
        std::vector<std::vector<std::string>> per_layer;
        size_t most = 0;
        for (const io::SelectedLayer& layer : layers) {
            per_layer.push_back(variance_names(*renderer, layer.name));
            most = std::max(most, per_layer.back().size());
        }
        const bool every_layer_has_one =
            std::none_of(per_layer.begin(), per_layer.end(), [](const auto& names) { return names.empty(); });
        for (size_t k = 0; every_layer_has_one && k < most; ++k) {
            std::vector<std::string> selectors;
            for (const std::vector<std::string>& names : per_layer)
                selectors.push_back(names[std::min(k, names.size() - 1)]);
            add_candidate(candidates[static_cast<size_t>(denoise::Auxiliary::Variance)],
                          std::move(selectors));
        }
    }
    return candidates;
}

std::vector<std::vector<std::vector<std::string>>>
layer_variance_candidates(const RendererChoice& choice, const std::vector<io::SelectedLayer>& layers)
{
    std::vector<std::vector<std::vector<std::string>>> candidates(layers.size());
    for (size_t i = 0; i < layers.size(); ++i)
        for (const RendererConvention* renderer : choice.conventions)
            for (std::string& name : variance_names(*renderer, layers[i].name))
                add_candidate(candidates[i], {std::move(name)});
    return candidates;
}

std::string describe_candidates(const std::vector<std::vector<std::string>>& candidates)
{
    std::vector<std::string> names;
    for (const std::vector<std::string>& selectors : candidates)
        names.push_back(fmt::format("{}", fmt::join(selectors, " + ")));
    return names.empty() ? "no name (the conventions have none)" : fmt::format("{}", fmt::join(names, ", "));
}

nlohmann::ordered_json renderer_json(const RendererChoice& choice, const std::vector<AuxiliaryFound>& lookups)
{
    nlohmann::ordered_json json;
    json["name"] = choice.name;
    json["detected_by"] = choice.detected_by;
    json["conventions"] = choice.table;
    nlohmann::ordered_json guides = nlohmann::ordered_json::object();
    nlohmann::ordered_json variance = nullptr;
    nlohmann::ordered_json layer_variance = nlohmann::ordered_json::array();
    for (const AuxiliaryFound& lookup : lookups) {
        nlohmann::ordered_json looked_for = nlohmann::ordered_json::array();
        for (const std::vector<std::string>& selectors : lookup.looked_for)
            looked_for.push_back(fmt::format("{}", fmt::join(selectors, " + ")));
        nlohmann::ordered_json entry{{"looked_for", looked_for}};
        entry["found"] = lookup.found.empty()
                             ? nlohmann::ordered_json(nullptr)
                             : nlohmann::ordered_json(fmt::format("{}", fmt::join(lookup.found, " + ")));
        if (!lookup.layer.empty()) {
            nlohmann::ordered_json layer_entry{{"layer", lookup.layer}};
            layer_entry.update(entry);
            layer_variance.push_back(layer_entry);
        } else if (lookup.kind == denoise::Auxiliary::Variance) {
            variance = entry;
        } else {
            guides[denoise::auxiliary_name(lookup.kind)] = entry;
        }
    }
    json["guides"] = guides;
    json["variance"] = variance;
    if (!layer_variance.empty()) // the layers denoised apart, each looked up on its own
        json["layer_variance"] = layer_variance;
    return json;
}

} // namespace modestack::app
