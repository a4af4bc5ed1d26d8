// Loads and checks the renderer conventions table (renderer_conventions.h):
// every field's type, every guide kind, every {placeholder}, and that the
// beauty's terms are light layers of the same renderer, so that a broken
// --conventions file is refused with one line naming it and the field.
#include "app/renderer_conventions.h"

#include "core/common/error.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <sstream>

namespace modestack::app {
namespace {

constexpr const char* kFormat = "modestack renderer conventions 1";

// A field of the table that is not what it should be; caught in parse_conventions.
struct FieldError {
    std::string where;
    std::string problem;
};

std::string text_field(const nlohmann::json& object, const char* key, const std::string& where, bool required)
{
    auto found = object.find(key);
    if (found == object.end()) {
        if (required)
            throw FieldError{where, fmt::format("has no \"{}\"", key)};
        return {};
    }
    if (!found->is_string())
        throw FieldError{fmt::format("{}.{}", where, key), "must be a string"};
    return found->get<std::string>();
}

// A list of layer names (or patterns); `templates` allows {layer}, nothing else.
std::vector<std::string> name_list(const nlohmann::json& value, const std::string& where, bool templates)
{
    if (!value.is_array())
        throw FieldError{where, "must be a list of names"};
    std::vector<std::string> names;
    for (size_t i = 0; i < value.size(); ++i) {
        const std::string at = fmt::format("{}[{}]", where, i);
        if (!value[i].is_string())
            throw FieldError{at, "must be a string"};
        std::string name = value[i].get<std::string>();
        std::string rest = name;
        if (templates)
            for (size_t at_layer; (at_layer = rest.find("{layer}")) != std::string::npos;)
                rest.erase(at_layer, 7);
        if (rest.find_first_of("{}") != std::string::npos)
            throw FieldError{at, fmt::format("'{}' has a placeholder other than {{layer}}", name)};
        names.push_back(std::move(name));
    }
    return names;
}

std::vector<std::string> optional_list(const nlohmann::json& object, const char* key,
                                       const std::string& where, bool templates)
{
    auto found = object.find(key);
    return found == object.end() ? std::vector<std::string>{}
                                 : name_list(*found, fmt::format("{}.{}", where, key), templates);
}

// An object whose keys are all in `known`: a misspelt key ("guide") is refused, not ignored.
void check_object(const nlohmann::json& value, const std::string& where,
                  std::initializer_list<const char*> known)
{
    if (!value.is_object())
        throw FieldError{where, "must be an object"};
    for (auto item = value.begin(); item != value.end();
         ++item) { // not a structured binding: clang 14 cannot capture one
        const std::string& key = item.key();
        if (std::none_of(known.begin(), known.end(), [&](const char* name) { return key == name; }))
            throw FieldError{where, fmt::format("has an unknown field \"{}\"", key)};
    }
}

void read_detection(const nlohmann::json& renderer, const std::string& where, RendererConvention& convention)
{
    auto detect = renderer.find("detect");
    if (detect == renderer.end())
        return;
    const std::string at = where + ".detect";
    check_object(*detect, at, {"attributes", "values", "layers"});
    convention.detect_attributes = optional_list(*detect, "attributes", at, false);
    convention.detect_layers = optional_list(*detect, "layers", at, false);
    if (auto values = detect->find("values"); values != detect->end()) {
        if (!values->is_array())
            throw FieldError{at + ".values", "must be a list of {\"attribute\", \"value\"} patterns"};
        for (size_t i = 0; i < values->size(); ++i) {
            const std::string rule_at = fmt::format("{}.values[{}]", at, i);
            check_object((*values)[i], rule_at, {"attribute", "value"});
            convention.detect_values.push_back({text_field((*values)[i], "attribute", rule_at, true),
                                                text_field((*values)[i], "value", rule_at, true)});
        }
    }
}

void read_light_layers(const nlohmann::json& renderer, const std::string& where,
                       RendererConvention& convention)
{
    auto lights = renderer.find("light_layers");
    if (lights == renderer.end())
        return;
    if (!lights->is_array())
        throw FieldError{where + ".light_layers",
                         "must be a list of {\"layer\", \"colour\", \"product\", \"parts\"}"};
    for (size_t i = 0; i < lights->size(); ++i) {
        const std::string at = fmt::format("{}.light_layers[{}]", where, i);
        check_object((*lights)[i], at, {"layer", "colour", "product", "parts"});
        LightLayer light{
            text_field((*lights)[i], "layer", at, true), text_field((*lights)[i], "colour", at, false),
            text_field((*lights)[i], "product", at, false), optional_list((*lights)[i], "parts", at, false)};
        if (light.layer.empty())
            throw FieldError{at + ".layer", "must not be empty"};
        if (convention.light_layer(light.layer))
            throw FieldError{at, fmt::format("names the light layer '{}' twice", light.layer)};
        convention.light_layers.push_back(std::move(light));
    }
    // A combined layer's parts are light layers of their own (listed anywhere in the list).
    for (size_t i = 0; i < convention.light_layers.size(); ++i)
        for (const std::string& part : convention.light_layers[i].parts)
            if (!convention.light_layer(part) || part == convention.light_layers[i].layer)
                throw FieldError{fmt::format("{}.light_layers[{}].parts", where, i),
                                 fmt::format("names '{}', which is not another of its light_layers", part)};
}

void read_guides_and_variance(const nlohmann::json& renderer, const std::string& where,
                              RendererConvention& convention)
{
    if (auto guides = renderer.find("guides"); guides != renderer.end()) {
        if (!guides->is_object())
            throw FieldError{where + ".guides", "must be an object"};
        for (const auto& [kind, names] : guides->items()) {
            if (std::find(guide_kinds().begin(), guide_kinds().end(), kind) == guide_kinds().end())
                throw FieldError{fmt::format("{}.guides.{}", where, kind),
                                 "is not one of albedo, normal, depth"};
            convention.guides[kind] = name_list(names, fmt::format("{}.guides.{}", where, kind), false);
        }
    }
    convention.variance = optional_list(renderer, "variance", where, true);
    if (auto by_layer = renderer.find("variance_by_layer"); by_layer != renderer.end()) {
        if (!by_layer->is_object())
            throw FieldError{where + ".variance_by_layer", "must be an object"};
        for (const auto& [layer, names] : by_layer->items())
            convention.variance_by_layer[layer] =
                name_list(names, fmt::format("{}.variance_by_layer.{}", where, layer), false);
    }
}

void read_beauty(const nlohmann::json& renderer, const std::string& where, RendererConvention& convention)
{
    auto beauty = renderer.find("beauty");
    if (beauty == renderer.end())
        return;
    const std::string at = where + ".beauty";
    check_object(*beauty, at, {"layer", "aliases", "sum"});
    convention.beauty_layer = text_field(*beauty, "layer", at, true);
    convention.beauty_aliases = optional_list(*beauty, "aliases", at, false);
    convention.beauty_sum = optional_list(*beauty, "sum", at, false);
    for (const std::string& term : convention.beauty_sum)
        if (!convention.light_layer(term))
            throw FieldError{at + ".sum",
                             fmt::format("names '{}', which is not one of its light_layers", term)};
}

RendererConvention read_renderer(const nlohmann::json& renderer, const std::string& where)
{
    check_object(renderer, where,
                 {"name", "aliases", "label", "detect", "light_layers", "guides", "variance",
                  "variance_by_layer", "beauty"});
    RendererConvention convention;
    convention.name = text_field(renderer, "name", where, true);
    if (convention.name.empty() || convention.name == "auto")
        throw FieldError{where + ".name", "must be a name other than \"\" and \"auto\""};
    convention.aliases = optional_list(renderer, "aliases", where, false);
    convention.label = text_field(renderer, "label", where, false);
    read_detection(renderer, where, convention);
    read_light_layers(renderer, where, convention);
    read_guides_and_variance(renderer, where, convention);
    read_beauty(renderer, where, convention);
    return convention;
}

std::string read_text(const std::string& path)
{
    std::error_code error;
    if (!std::filesystem::is_regular_file(path, error))
        throw bad_input(path, "the renderer conventions file does not exist or is not a file");
    std::ifstream file(path, std::ios::binary);
    std::ostringstream text;
    text << file.rdbuf();
    if (!file && !file.eof())
        throw bad_input(path, "the renderer conventions file cannot be read");
    return text.str();
}

// share/modestack/conventions.json next to the installed binary, or "".
std::string installed_conventions_path()
{
    std::error_code error;
    std::filesystem::path binary = std::filesystem::read_symlink("/proc/self/exe", error);
    if (error)
        return {};
    std::filesystem::path candidate =
        binary.parent_path() / MODESTACK_CONVENTIONS_FROM_BINARY / "conventions.json";
    return std::filesystem::is_regular_file(candidate, error) ? candidate.lexically_normal().string() : "";
}

} // namespace

const LightLayer* RendererConvention::light_layer(const std::string& layer) const
{
    for (const LightLayer& light : light_layers)
        if (light.layer == layer)
            return &light;
    return nullptr;
}

const RendererConvention* ConventionTable::find(const std::string& name) const
{
    for (const RendererConvention& renderer : renderers)
        if (renderer.name == name ||
            std::find(renderer.aliases.begin(), renderer.aliases.end(), name) != renderer.aliases.end())
            return &renderer;
    return nullptr;
}

std::string ConventionTable::names() const
{
    std::vector<std::string> names;
    for (const RendererConvention& renderer : renderers)
        names.push_back(renderer.name);
    return fmt::format("{}", fmt::join(names, ", "));
}

ConventionTable parse_conventions(const std::string& json_text, const std::string& source)
{
    nlohmann::json document;
    try {
        document = nlohmann::json::parse(json_text);
    } catch (const nlohmann::json::exception& error) {
        throw bad_input(source, fmt::format("the renderer conventions are not valid JSON: {}", error.what()));
    }
    ConventionTable table;
    table.source = source;
    try {
        check_object(document, "the table", {"format", "about", "renderers"});
        if (text_field(document, "format", "the table", true) != kFormat)
            throw FieldError{"format", fmt::format("must be \"{}\"", kFormat)};
        auto renderers = document.find("renderers");
        if (renderers == document.end() || !renderers->is_array() || renderers->empty())
            throw FieldError{"renderers", "must be a list of at least one renderer"};
        for (size_t i = 0; i < renderers->size(); ++i) {
            RendererConvention convention = read_renderer((*renderers)[i], fmt::format("renderers[{}]", i));
            for (const std::string& name : [&] {
                     std::vector<std::string> all{convention.name};
                     all.insert(all.end(), convention.aliases.begin(), convention.aliases.end());
                     return all;
                 }())
                if (table.find(name))
                    throw FieldError{fmt::format("renderers[{}]", i), fmt::format("names '{}' again", name)};
            table.renderers.push_back(std::move(convention));
        }
    } catch (const FieldError& error) {
        throw bad_input(source, fmt::format("renderer conventions: {} {}", error.where, error.problem));
    }
    return table;
}

ConventionTable load_conventions(const std::string& path)
{
    if (!path.empty())
        return parse_conventions(read_text(path), path);
    if (std::string installed = installed_conventions_path(); !installed.empty())
        return parse_conventions(read_text(installed), installed);
    return parse_conventions(built_in_conventions_json(), "built-in");
}

} // namespace modestack::app
