#include "app/whitening_choice.h"

#include "core/common/error.h"

#include <fmt/format.h>

#include <algorithm>

namespace modestack::app {
namespace {

std::string reason_without_weights(const std::string& mode, bool transformed, bool has_variance)
{
    return mode == "off"   ? "off"
           : !has_variance ? "no variance layer"
           : transformed   ? "off under --transform"
                           : "";
}

} // namespace

std::vector<WhitenedPart> choose_whitening(const std::string& mode, bool transformed,
                                           denoise::FrameSource& source, const denoise::Settings& settings,
                                           const VarianceNames& names)
{
    const denoise::ShotShape shape = source.shape();
    std::vector<WhitenedPart> parts;
    if (settings.layer_channels.size() < 2) {
        const bool has_variance =
            mode != "off" && source.auxiliary_channels(denoise::Auxiliary::Variance) == shape.channels;
        if (mode == "on" && !has_variance)
            throw bad_input(
                names.input,
                fmt::format("--whiten on needs a variance layer with one channel per denoised channel "
                            "in every frame (looked for {}; see --renderer)",
                            names.shot));
        WhitenedPart& part = parts.emplace_back();
        part.reason = reason_without_weights(mode, transformed, has_variance);
        if (part.reason.empty()) {
            part.weights = denoise::whitening_weights(source);
            part.reason = "variance layer";
        }
        return parts;
    }
    for (size_t i = 0; i < settings.layer_channels.size(); ++i) {
        const int layer = static_cast<int>(i);
        const int channels = settings.layer_channels[i];
        const bool has_variance = mode != "off" && source.layer_variance_channels(layer) == channels;
        if (mode == "on" && !has_variance)
            throw bad_input(
                names.input,
                fmt::format("--whiten on needs a variance layer of {} in every frame (looked for {}); "
                            "--whiten auto whitens only the layers that have one",
                            names.layers.at(i), names.layer_shots.at(i)));
        WhitenedPart& part = parts.emplace_back();
        part.layer = names.layers.at(i);
        part.reason = reason_without_weights(mode, transformed, has_variance);
        if (part.reason.empty()) {
            part.weights = denoise::layer_whitening_weights(source, layer, channels);
            part.reason = "variance layer";
        }
    }
    return parts;
}

void apply_whitening(const std::vector<WhitenedPart>& parts, denoise::Settings& settings)
{
    settings.whitening = nullptr;
    settings.layer_whitening.clear();
    if (parts.size() == 1 && parts.front().layer.empty()) {
        if (parts.front().weights)
            settings.whitening = &parts.front().weights->weights;
        return;
    }
    for (const WhitenedPart& part : parts)
        settings.layer_whitening.push_back(part.weights ? &part.weights->weights : nullptr);
}

nlohmann::ordered_json whitened_part_json(const WhitenedPart& part)
{
    nlohmann::ordered_json json{{"mode", part.weights ? "on" : "off"}, {"reason", part.reason}};
    if (const auto& weights = part.weights)
        json.update({{"mean_variance", weights->mean_variance},
                     {"variance_floor", weights->floor},
                     {"floored_samples", weights->floored_samples},
                     {"weight_min", weights->smallest},
                     {"weight_max", weights->largest}});
    return json;
}

nlohmann::ordered_json whitening_json(const std::vector<WhitenedPart>& parts)
{
    if (parts.size() == 1 && parts.front().layer.empty())
        return whitened_part_json(parts.front());
    const auto whitened = std::count_if(parts.begin(), parts.end(),
                                        [](const WhitenedPart& part) { return part.weights.has_value(); });
    std::vector<std::string> reasons;
    nlohmann::ordered_json layers = nlohmann::ordered_json::array();
    for (const WhitenedPart& part : parts) {
        reasons.push_back(fmt::format("{}: {}", part.layer, part.reason));
        nlohmann::ordered_json entry{{"layer", part.layer}};
        entry.update(whitened_part_json(part));
        layers.push_back(entry);
    }
    return {{"mode", whitened == 0                                           ? "off"
                     : whitened == static_cast<std::ptrdiff_t>(parts.size()) ? "on"
                                                                             : "per layer"},
            {"reason", fmt::format("each layer on its own variance ({})", fmt::join(reasons, ", "))},
            {"layers", layers}};
}

} // namespace modestack::app
