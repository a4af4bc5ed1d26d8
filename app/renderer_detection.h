// Which renderer wrote a shot, and the layer names the denoiser looks for in
// it: the renderer is detected from the first frame's header attributes and
// layer names by the rules of the conventions table (renderer_conventions.h),
// or named with --renderer; the guide and variance names of the denoised
// layers then come from its row of the table. The one place for both rules.
#pragma once

#include "app/renderer_conventions.h"
#include "core/denoise/frame_stream.h"
#include "io/frame_header.h"
#include "io/layers.h"

#include <nlohmann/json.hpp>

#include <array>
#include <string>
#include <vector>

namespace modestack::app {

/// The conventions a shot is read with.
struct RendererChoice {
    /// The renderer's row, or every row in table order when nothing matched
    /// (each one's names are tried, first found wins).
    std::vector<const RendererConvention*> conventions;
    std::string name;        ///< "arnold", or "unknown"
    std::string detected_by; ///< "--renderer arnold", "header attribute arnold/version", ...
    std::string table;       ///< the table's source: a file, or "built-in"
};

/// The renderer `requested` names (--renderer; a usage error when the table has
/// no such name), or with "auto" the one `header` shows: the first renderer
/// (table order) one of whose attribute name rules matches, else one of whose
/// attribute value rules matches, else the one whose layer patterns match most
/// layers of the file (ties: table order).
RendererChoice choose_renderer(const ConventionTable& table, const std::string& requested,
                               const io::FrameHeader& header);

/// Throws a usage error when `requested` is neither "auto" nor a renderer of `table`.
void check_renderer_name(const ConventionTable& table, const std::string& requested);

/// The prefix the table's names are relative to: "ViewLayer." of "ViewLayer.DiffInd", "" of "DiffInd".
std::string layer_prefix(const std::string& layer);

/// The layer selectors tried for each auxiliary kind (by denoise::Auxiliary),
/// best first; each candidate is one selector list for io::SequenceReader (the
/// variance candidate has one layer per denoised layer).
using AuxiliaryCandidates = std::array<std::vector<std::vector<std::string>>, 4>;

/// The candidates of `choice` for the denoised `layers`: guide names after the
/// prefix of the first layer (`ViewLayer.` of `ViewLayer.DiffInd`), variance
/// names per layer after its own prefix.
AuxiliaryCandidates auxiliary_candidates(const RendererChoice& choice,
                                         const std::vector<io::SelectedLayer>& layers);

/// The variance names of each of `layers` on its own (the layers denoised
/// apart), best first, each candidate a list of one selector: unlike the
/// variance of auxiliary_candidates, a layer's names are offered whether or not
/// the other layers have a variance.
std::vector<std::vector<std::vector<std::string>>>
layer_variance_candidates(const RendererChoice& choice, const std::vector<io::SelectedLayer>& layers);

/// "ViewLayer.DiffCol, ViewLayer.Denoising Albedo": the candidates of one kind, for messages.
std::string describe_candidates(const std::vector<std::vector<std::string>>& candidates);

/// What a lookup of one auxiliary kind found.
struct AuxiliaryFound {
    denoise::Auxiliary kind;
    std::string layer; ///< a variance of one layer denoised apart ("": of the whole selection)
    std::vector<std::vector<std::string>> looked_for;
    std::vector<std::string> found; ///< the layers read, empty when none was found
};

/// The --json block "renderer": the convention used, how it was chosen, and the
/// names each looked-up guide and variance was searched and found under.
nlohmann::ordered_json renderer_json(const RendererChoice& choice,
                                     const std::vector<AuxiliaryFound>& lookups);

} // namespace modestack::app
