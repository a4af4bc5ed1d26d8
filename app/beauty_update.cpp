// --update-beauty: the plan from the renderer conventions and its application
// to the native rows the sink copies (beauty_update.h).
#include "app/beauty_update.h"

#include "core/common/error.h"
#include "io/layers.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

namespace modestack::app {
namespace {

// The full name of a table name after `prefix`; the unnamed layer stays "" (bare R, G, B).
std::string full_name(const std::string& prefix, const std::string& name)
{
    return name.empty() ? "" : prefix + name;
}

std::string channel_of(const std::string& layer, const std::string& component)
{
    return layer.empty() ? component : layer + "." + component;
}

std::string shown(const std::string& layer)
{
    return layer.empty() ? "the unnamed R, G, B" : layer;
}

std::vector<std::string> components_of(const io::SelectedLayer& layer)
{
    std::vector<std::string> components;
    for (const std::string& channel : layer.channel_names) {
        std::string name, component;
        io::split_channel_name(channel, name, component);
        components.push_back(component);
    }
    return components;
}

// "ViewLayer.DiffCol * ViewLayer.DiffDir + ... + ViewLayer.Emit": the beauty's sum as the table gives it,
// `beauty` its layer as the file names it.
std::string composition(const RendererConvention& convention, const std::string& prefix,
                        const std::string& beauty)
{
    std::vector<std::string> terms;
    for (const std::string& term : convention.beauty_sum) {
        const LightLayer* light = convention.light_layer(term);
        terms.push_back(light->colour.empty()
                            ? prefix + term
                            : fmt::format("{}{} * {}{}", prefix, light->colour, prefix, term));
    }
    return fmt::format("{} = {}", shown(full_name(prefix, beauty)), fmt::join(terms, " + "));
}

// Fills `plan`'s targets, or returns why the beauty's composition over the denoised layers is not known.
std::string compose(const RendererChoice& renderer, const io::SequenceReader& reader, BeautyPlan& plan)
{
    if (renderer.conventions.size() != 1)
        return fmt::format(
            "the renderer is unknown ({}): its beauty's composition is not known (name it with "
            "--renderer)",
            renderer.detected_by);
    const RendererConvention& convention = *renderer.conventions.front();
    if (convention.beauty_sum.empty())
        return fmt::format("the {} conventions ({}) give no composition of the beauty", convention.name,
                           renderer.table);
    const std::vector<io::SelectedLayer>& layers = reader.layers();
    const std::string prefix = layer_prefix(layers.front().name);
    const std::string file = reader.sequence().files.front();
    const std::vector<std::string>& channels = reader.channel_names(0);
    const std::set<std::string> present(channels.begin(), channels.end());
    auto has_layer = [&](const std::string& layer, const std::vector<std::string>& components) {
        return std::all_of(components.begin(), components.end(),
                           [&](const std::string& c) { return present.count(channel_of(layer, c)) > 0; });
    };
    auto in_sum = [&](const std::string& name) {
        return std::find(convention.beauty_sum.begin(), convention.beauty_sum.end(), name) !=
               convention.beauty_sum.end();
    };
    const std::vector<std::string> components = components_of(layers.front());
    // The beauty's name in this file: the table's, else the first of its aliases the file has.
    std::string beauty_layer = convention.beauty_layer;
    if (!has_layer(full_name(prefix, beauty_layer), components))
        for (const std::string& alias : convention.beauty_aliases)
            if (has_layer(full_name(prefix, alias), components)) {
                beauty_layer = alias;
                break;
            }
    BeautyTarget beauty{full_name(prefix, beauty_layer), components, {}};
    std::vector<BeautyTarget> products;
    std::map<std::string, std::string> holder; // a term of the sum -> the denoised layer that holds it
    int offset = 0;
    for (const io::SelectedLayer& layer : layers) {
        const int first = offset;
        offset += static_cast<int>(layer.channel_names.size());
        if (layer_prefix(layer.name) != prefix)
            return fmt::format("the denoised layers {} and {} have different prefixes: one beauty per run",
                               layers.front().name, layer.name);
        if (components_of(layer) != components)
            return fmt::format("the denoised layers {} and {} have different components", layers.front().name,
                               layer.name);
        const std::string short_name = layer.name.substr(prefix.size());
        if (short_name == beauty_layer)
            return fmt::format("the beauty {} is itself denoised", shown(layer.name));
        const LightLayer* light = convention.light_layer(short_name);
        if (!light)
            return fmt::format(
                "{} is not a light layer of the {} conventions: its share of the beauty is not "
                "known",
                layer.name, convention.name);
        std::vector<std::string> terms;
        std::string product;
        if (in_sum(short_name))
            terms = {short_name};
        else if (!light->product.empty() && in_sum(light->product))
            terms = {product = light->product};
        else if (!light->parts.empty() && std::all_of(light->parts.begin(), light->parts.end(), in_sum))
            terms = light->parts;
        else
            return fmt::format(
                "{} is a light layer of the {} conventions but not a term of their beauty's sum "
                "({})",
                layer.name, convention.name, composition(convention, prefix, beauty_layer));
        for (const std::string& term : terms) {
            auto [held, added] = holder.emplace(term, layer.name);
            if (!added)
                return fmt::format(
                    "{} and {} both hold {}{}: the beauty would count that light twice (denoise "
                    "them in separate runs)",
                    held->second, layer.name, prefix, term);
        }
        BeautyTerm term{layer.name, light->colour.empty() ? "" : prefix + light->colour, {}, {}};
        for (size_t c = 0; c < components.size(); ++c)
            term.selected_offsets.push_back(first + static_cast<int>(c));
        if (std::all_of(layer.sigma_names.begin(), layer.sigma_names.end(),
                        [&](const std::string& name) { return present.count(name) > 0; }))
            term.input_sigma = layer.sigma_names; // denoised before: its term of an input beauty sigma
        if (!term.colour.empty() && !has_layer(term.colour, components))
            return fmt::format("{} has no colour layer {} (the {} conventions multiply {} by it)", file,
                               term.colour, convention.name, layer.name);
        beauty.terms.push_back(term);
        // A raw layer's product AOV (V-Ray, Redshift) changes by the same amount, when the input has it.
        if (!product.empty() && has_layer(prefix + product, components))
            products.push_back({prefix + product, components, {term}});
    }
    if (!has_layer(beauty.layer, components))
        return fmt::format("{} has no beauty {} with the channels {} (the {} conventions' beauty)", file,
                           shown(beauty.layer), fmt::join(components, ", "), convention.name);
    // The beauty's sigma: appended, or (an earlier run's output) rewritten in its own channels.
    std::vector<std::string> sigma_names;
    size_t in_input = 0;
    for (const std::string& component : components) {
        sigma_names.push_back(
            channel_of(beauty.layer.empty() ? "sigma" : beauty.layer + ".sigma", component));
        in_input += present.count(sigma_names.back());
    }
    if (in_input != 0 && in_input != sigma_names.size())
        return fmt::format("{} has some of the beauty's sigma channels {} but not all", file,
                           fmt::join(sigma_names, ", "));
    if (in_input == 0)
        for (BeautyTerm& term : beauty.terms)
            term.input_sigma.clear(); // no input beauty sigma to take its term out of
    plan.composition = composition(convention, prefix, beauty_layer);
    plan.targets.push_back(std::move(beauty));
    plan.targets.insert(plan.targets.end(), products.begin(), products.end());
    (in_input ? plan.sigma_in_place : plan.sigma_names) = std::move(sigma_names);
    return {};
}

} // namespace

BeautyPlan plan_beauty_update(const RendererChoice& renderer, const io::SequenceReader& reader,
                              const std::string& requested, bool linear)
{
    BeautyPlan plan;
    plan.requested = requested;
    if (requested == "off") {
        plan.reason = "--no-update-beauty";
        return plan;
    }
    std::string why_not = compose(renderer, reader, plan);
    if (why_not.empty() && !linear)
        why_not = "the input is not scene-linear: the beauty's sum holds in linear light only";
    if (!why_not.empty()) {
        if (requested == "on")
            throw usage_error(fmt::format("--update-beauty: {}", why_not));
        plan = BeautyPlan{};
        plan.requested = requested;
        plan.reason = why_not;
        return plan;
    }
    plan.update = true;
    plan.reason = fmt::format("the {} conventions compose the beauty: {}", renderer.name, plan.composition);
    return plan;
}

std::string beauty_formula(const BeautyTarget& target)
{
    std::vector<std::string> terms;
    for (const BeautyTerm& term : target.terms)
        terms.push_back(term.colour.empty()
                            ? fmt::format("(denoised - noisy {})", term.denoised)
                            : fmt::format("{} * (denoised - noisy {})", term.colour, term.denoised));
    return fmt::format("{} += {}", shown(target.layer), fmt::join(terms, " + "));
}

std::vector<std::string> rewritten_layers(const BeautyPlan& plan)
{
    std::vector<std::string> layers;
    if (plan.update)
        for (const BeautyTarget& target : plan.targets)
            layers.push_back(target.layer);
    if (plan.update && !plan.sigma_in_place.empty()) { // the input's beauty sigma, rewritten
        std::string layer, component;
        io::split_channel_name(plan.sigma_in_place.front(), layer, component);
        layers.push_back(layer);
    }
    return layers;
}

nlohmann::ordered_json beauty_json(const BeautyPlan& plan)
{
    nlohmann::ordered_json json;
    json["requested"] = plan.requested;
    json["updated"] = plan.update;
    json["reason"] = plan.reason;
    if (!plan.update)
        return json;
    const BeautyTarget& beauty = plan.targets.front();
    json["layer"] = beauty.layer;
    json["channels"] = [&] {
        std::vector<std::string> channels;
        for (const std::string& component : beauty.components)
            channels.push_back(channel_of(beauty.layer, component));
        return channels;
    }();
    json["formula"] = beauty_formula(beauty);
    const bool in_place = !plan.sigma_in_place.empty();
    auto variance = [](const BeautyTerm& term, const std::string& sigma) {
        return term.colour.empty() ? fmt::format("{}^2", sigma)
                                   : fmt::format("{}^2 * {}^2", term.colour, sigma);
    };
    std::string variances;
    if (in_place) {
        std::string layer, component;
        io::split_channel_name(plan.sigma_in_place.front(), layer, component);
        variances = fmt::format("{} (input)^2", layer);
        for (const BeautyTerm& term : beauty.terms)
            if (!term.input_sigma.empty())
                variances += " - " + variance(term, term.denoised + ".sigma (input)");
    }
    for (const BeautyTerm& term : beauty.terms)
        variances += (variances.empty() ? "" : " + ") + variance(term, term.denoised + ".sigma");
    json["sigma"] = {{"channels", in_place ? plan.sigma_in_place : plan.sigma_names},
                     {"rewritten", in_place},
                     {"formula", fmt::format("sqrt({})", variances)},
                     {"meaning",
                      "the standard error the denoised layers leave in the beauty; its other terms "
                      "keep their render noise, which is not counted"}};
    nlohmann::ordered_json products = nlohmann::ordered_json::array();
    for (size_t k = 1; k < plan.targets.size(); ++k)
        products.push_back({{"layer", plan.targets[k].layer}, {"formula", beauty_formula(plan.targets[k])}});
    json["products"] = products;
    json["alpha"] = "untouched";
    return json;
}

BeautyUpdate::BeautyUpdate(const io::SequenceReader& reader, BeautyPlan plan)
    : m_reader(reader), m_plan(std::move(plan))
{
    for (int frame = 0; frame < reader.frame_count(); ++frame) {
        const std::vector<std::string>& names = reader.channel_names(frame);
        auto index = [&](const std::string& channel) {
            const auto found = std::find(names.begin(), names.end(), channel);
            if (found == names.end())
                throw bad_input(reader.sequence().files[static_cast<size_t>(frame)],
                                fmt::format("channel '{}' (--update-beauty) not found", channel));
            return static_cast<int>(found - names.begin());
        };
        FrameChannels channels;
        for (const BeautyTarget& target : m_plan.targets) {
            channels.target.emplace_back();
            channels.colour.emplace_back();
            for (const std::string& component : target.components)
                channels.target.back().push_back(index(channel_of(target.layer, component)));
            for (const BeautyTerm& term : target.terms) {
                channels.colour.back().emplace_back();
                if (!term.colour.empty())
                    for (const std::string& component : target.components)
                        channels.colour.back().back().push_back(index(channel_of(term.colour, component)));
            }
        }
        for (const std::string& channel : m_plan.sigma_in_place)
            channels.sigma_in_place.push_back(index(channel));
        for (const BeautyTerm& term : m_plan.targets.front().terms) {
            channels.input_sigma.emplace_back();
            for (const std::string& channel : term.input_sigma)
                channels.input_sigma.back().push_back(index(channel));
        }
        m_frames.push_back(std::move(channels));
    }
}

void BeautyUpdate::apply(int frame_index, std::size_t pixels, unsigned char* native, const float* rebuilt,
                         const float* sigma, float* beauty_sigma) const
{
    const FrameChannels& channels = m_frames.at(static_cast<size_t>(frame_index));
    const std::size_t selected = static_cast<std::size_t>(m_reader.selected_channel_count());
    thread_local std::vector<float> noisy, values, sigma_in;
    thread_local std::vector<std::vector<float>> colours, term_sigma_in;
    noisy.resize(pixels * selected);
    m_reader.selected_from_native(frame_index, native, pixels, noisy.data());
    // The input beauty's sigma and the input sigma of its terms denoised before, before any rewrite.
    const bool in_place = !channels.sigma_in_place.empty();
    if (in_place) {
        sigma_in.resize(pixels * channels.sigma_in_place.size());
        m_reader.channels_from_native(frame_index, native, pixels, channels.sigma_in_place, sigma_in.data());
        term_sigma_in.resize(channels.input_sigma.size());
        for (size_t k = 0; k < channels.input_sigma.size(); ++k)
            if (!channels.input_sigma[k].empty()) {
                term_sigma_in[k].resize(pixels * channels.input_sigma[k].size());
                m_reader.channels_from_native(frame_index, native, pixels, channels.input_sigma[k],
                                              term_sigma_in[k].data());
            }
    }
    for (size_t t = 0; t < m_plan.targets.size(); ++t) {
        const BeautyTarget& target = m_plan.targets[t];
        const std::size_t components = target.components.size();
        values.resize(pixels * components);
        m_reader.channels_from_native(frame_index, native, pixels, channels.target[t], values.data());
        colours.resize(target.terms.size());
        for (size_t k = 0; k < target.terms.size(); ++k) {
            colours[k].resize(pixels * components);
            if (!channels.colour[t][k].empty())
                m_reader.channels_from_native(frame_index, native, pixels, channels.colour[t][k],
                                              colours[k].data());
        }
        for (std::size_t p = 0; p < pixels; ++p)
            for (std::size_t c = 0; c < components; ++c) {
                double change = 0, variance = 0, replaced = 0;
                for (size_t k = 0; k < target.terms.size(); ++k) {
                    const std::size_t at =
                        p * selected + static_cast<std::size_t>(target.terms[k].selected_offsets[c]);
                    const double colour =
                        channels.colour[t][k].empty() ? 1.0 : colours[k][p * components + c];
                    const double difference = colour * (static_cast<double>(rebuilt[at]) - noisy[at]);
                    // A non-finite noisy value (replaced by the engine) or colour leaves the target as it
                    // was.
                    if (std::isfinite(difference))
                        change += difference;
                    if (sigma)
                        variance += colour * colour * static_cast<double>(sigma[at]) * sigma[at];
                    if (t == 0 && in_place && !channels.input_sigma[k].empty()) {
                        const double before = term_sigma_in[k][p * components + c];
                        replaced += colour * colour * before * before;
                    }
                }
                float& value = values[p * components + c];
                value = static_cast<float>(value + change);
                if (t != 0)
                    continue;
                if (!std::isfinite(variance))
                    variance = 0;
                if (in_place) {
                    // The input's sigma keeps the other layers' terms (independent errors: in quadrature).
                    float& combined = sigma_in[p * components + c];
                    const double kept = static_cast<double>(combined) * combined - replaced;
                    const double total = std::max(0.0, std::isfinite(kept) ? kept : 0.0) + variance;
                    if (std::isfinite(static_cast<double>(combined)))
                        combined = static_cast<float>(std::sqrt(total));
                } else {
                    beauty_sigma[p * components + c] = static_cast<float>(std::sqrt(variance));
                }
            }
        m_reader.channels_to_native(frame_index, native, pixels, channels.target[t], values.data());
    }
    if (in_place)
        m_reader.channels_to_native(frame_index, native, pixels, channels.sigma_in_place, sigma_in.data());
}

} // namespace modestack::app
