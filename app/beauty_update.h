// --update-beauty (docs/design.md, "The beauty kept in step"): denoising a light
// layer changes it by denoised − noisy, so the beauty, a pass-through layer,
// would no longer equal the composite of its AOVs. The plan decides from the
// renderer conventions (renderer_conventions.h) whether the beauty's
// composition over the denoised layers is known, and why not; BeautyUpdate then
// rewrites, in the native rows the sink copies, the beauty (and the product AOV
// of a raw layer) as  target + Σ_k colour_k × (denoised_k − noisy_k)  and gives
// the beauty's sigma  sqrt(Σ_k colour_k² σ_k²), or, when the input's beauty has a
// sigma already (the output of an earlier run), that sigma combined with the new
// terms in quadrature, in its own channels.
#pragma once

#include "app/renderer_detection.h"
#include "io/sequence_reader.h"

#include <nlohmann/json.hpp>

#include <cstddef>
#include <string>
#include <vector>

namespace modestack::app {

/// One denoised layer's share of a rewritten layer.
struct BeautyTerm {
    std::string denoised;              ///< the denoised layer, full name
    std::string colour;                ///< its colour AOV, full name ("" = × 1)
    std::vector<int> selected_offsets; ///< of each component in a selected row
    /// The layer's sigma channels in the input (denoised before), by component: its
    /// term in the input beauty's sigma, replaced by the new one. Empty: none.
    std::vector<std::string> input_sigma;
};

/// A pass-through layer rewritten: the beauty, or a raw layer's product AOV.
struct BeautyTarget {
    std::string layer;                   ///< full name ("" = the bare R, G, B)
    std::vector<std::string> components; ///< "R", "G", "B" (never A: alpha is coverage)
    std::vector<BeautyTerm> terms;
};

/// What --update-beauty does for a shot, and why.
struct BeautyPlan {
    std::string requested = "auto"; ///< auto, on (--update-beauty), off (--no-update-beauty)
    bool update = false;
    std::string reason;                   ///< why the beauty is (not) updated
    std::string composition;              ///< the beauty's sum as the conventions give it
    std::vector<BeautyTarget> targets;    ///< [0] the beauty, then product AOVs
    /// The beauty's sigma channels appended to the output; empty when the input has
    /// them (`sigma_in_place`).
    std::vector<std::string> sigma_names;
    /// The beauty's sigma channels of the input (an earlier run's), rewritten in
    /// place as sqrt(σ_in² − Σ_k colour_k² σ_k,in² + Σ_k colour_k² σ_k²): the errors
    /// of the beauty's layers are independent, and a layer denoised again replaces
    /// its own term (σ_k,in, `BeautyTerm::input_sigma`, 0 for a layer not denoised before).
    std::vector<std::string> sigma_in_place;
};

/// The plan for the denoised layers of `reader` under `renderer`'s conventions:
/// an update when exactly one renderer's conventions apply, they compose the
/// beauty, every denoised layer is a term of its sum (or a combined layer of
/// terms, or a raw layer of a term), no light counts twice, and the beauty and
/// colour layers are in the input with the denoised layers' components.
/// `requested` (auto, on, off) and `linear` (the input is scene-linear: the sum
/// holds in linear light only) decide the rest; "on" where the composition is
/// not known is a usage error naming why.
BeautyPlan plan_beauty_update(const RendererChoice& renderer, const io::SequenceReader& reader,
                              const std::string& requested, bool linear);

/// The text of a target's update: "ViewLayer.Combined += ViewLayer.DiffCol * (denoised - noisy
/// ViewLayer.DiffInd)".
std::string beauty_formula(const BeautyTarget& target);

/// The layers a plan rewrites (its targets), by full name: what --only-denoised
/// keeps of the pass-through layers.
std::vector<std::string> rewritten_layers(const BeautyPlan& plan);

/// The --json block "beauty".
nlohmann::ordered_json beauty_json(const BeautyPlan& plan);

/// Applies a plan to the native rows of each frame (the sink's copy of them).
class BeautyUpdate {
public:
    /// Resolves the plan's channels in every frame of `reader`, which must outlive this object.
    BeautyUpdate(const io::SequenceReader& reader, BeautyPlan plan);
    const BeautyPlan& plan() const { return m_plan; }
    /// Rewrites the targets in `native` (`pixels` pixels of frame `frame_index`,
    /// read_native's layout, still holding the noisy denoised layers) from
    /// `rebuilt` and writes the beauty's sigma, one value per component, to
    /// `beauty_sigma` (`sigma` null: zero), or with `sigma_in_place` into
    /// `native` (`beauty_sigma` unused).
    void apply(int frame_index, std::size_t pixels, unsigned char* native, const float* rebuilt,
               const float* sigma, float* beauty_sigma) const;

private:
    struct FrameChannels {
        std::vector<std::vector<int>> target;              ///< by target, by component
        std::vector<std::vector<std::vector<int>>> colour; ///< by target, by term ({} = × 1)
        std::vector<int> sigma_in_place;                   ///< by component ({} = appended)
        std::vector<std::vector<int>> input_sigma;         ///< of the beauty's terms, by component
    };
    const io::SequenceReader& m_reader;
    BeautyPlan m_plan;
    std::vector<FrameChannels> m_frames;
};

} // namespace modestack::app
