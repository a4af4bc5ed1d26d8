// The renderer conventions table (share/conventions.json, docs/design.md,
// "Renderer conventions"): per renderer, how its frames are recognised, its
// light AOVs and the colour AOV each is multiplied by in the beauty, the guide
// and variance AOVs the denoiser looks for, and how the beauty is composed. The
// rules are data: this file only loads and checks the table; detection and the
// name lookup are in app/renderer_detection.h.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace modestack::app {

/// A light AOV. In the beauty it counts as colour × layer (× 1 when `colour`
/// is empty: the layer already holds the surface colour); `product`, when set,
/// is the AOV that holds that product (V-Ray's VRayGlobalIllumination for
/// VRayRawGlobalIllumination); `parts`, when set, are the light layers whose
/// sum this layer holds (Arnold's diffuse = diffuse_direct + diffuse_indirect),
/// so that --update-beauty counts each light once.
struct LightLayer {
    std::string layer;
    std::string colour;
    std::string product;
    std::vector<std::string> parts;
};

/// What a header attribute's value must look like (both fnmatch patterns).
struct AttributeValueRule {
    std::string attribute;
    std::string value;
};

/// One renderer's row of the table. Layer names are relative to the prefix
/// of the denoised layer (`ViewLayer.` for Cycles' ViewLayer.DiffInd).
struct RendererConvention {
    std::string name;                 ///< what --renderer takes: "cycles", "arnold", ...
    std::vector<std::string> aliases; ///< other names --renderer takes ("prman")
    std::string label;                ///< for people: "Pixar RenderMan (...)"
    /// Detection: fnmatch patterns on header attribute names, on attribute
    /// values, and on layer names (the whole name or its last dot-part).
    std::vector<std::string> detect_attributes;
    std::vector<AttributeValueRule> detect_values;
    std::vector<std::string> detect_layers;
    std::vector<LightLayer> light_layers;
    /// Guide layer names, best first, for "albedo", "normal" and "depth".
    std::map<std::string, std::vector<std::string>> guides;
    /// Variance layer names of a denoised layer, best first; {layer} is its name.
    std::vector<std::string> variance;
    /// Names tried before `variance` for one layer name ("" is the unnamed R, G, B).
    std::map<std::string, std::vector<std::string>> variance_by_layer;
    std::string beauty_layer;            ///< "" = the unnamed R, G, B, A
    /// Names the beauty has where `beauty_layer` is not in the file, tried in
    /// order: a multi-part file's beauty is a named part ("RGBA"), never unnamed.
    std::vector<std::string> beauty_aliases;
    std::vector<std::string> beauty_sum; ///< light layers whose colour × layer sum to the beauty

    /// The light layer named `layer`, or nullptr.
    const LightLayer* light_layer(const std::string& layer) const;
};

/// The whole table and where it came from.
struct ConventionTable {
    std::string source; ///< the file read, or "built-in"
    std::vector<RendererConvention> renderers;

    /// The renderer called `name` (or one of its aliases), or nullptr.
    const RendererConvention* find(const std::string& name) const;
    /// "modestack, cycles, arnold, ...": for messages.
    std::string names() const;
};

/// The guide kinds the table names, in the order the mode filter lists them.
inline const std::vector<std::string>& guide_kinds()
{
    static const std::vector<std::string> kinds{"albedo", "normal", "depth"};
    return kinds;
}

/// Parses and checks a table; `source` names it in errors (bad input, one line).
ConventionTable parse_conventions(const std::string& json_text, const std::string& source);

/// The table --conventions FILE names, or ("" ) the one shipped with modestack:
/// share/modestack/conventions.json next to the installed binary, else the copy
/// compiled into it (the same file at build time). Throws Error naming the file.
ConventionTable load_conventions(const std::string& path);

/// The text of share/conventions.json as it was when modestack was built.
const char* built_in_conventions_json();

} // namespace modestack::app
