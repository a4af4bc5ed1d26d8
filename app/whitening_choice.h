// `denoise --whiten`: which parts of a shot are whitened and why, the one place
// for the rule (core/denoise/whitening.h computes the weights).
// One set of modes (one layer, or --joint): the whole selection is whitened when
// every selected channel has a variance. Layers apart (each on its own modes):
// each layer that has its own variance layer is whitened by weights from that
// variance alone, exactly those of a run of the layer alone; a layer without
// one is not. auto whitens what has a variance; on wants every part to have
// one; off whitens nothing, nor does --transform (the variance is of the
// untransformed values).
#pragma once

#include "core/denoise/engine.h"
#include "core/denoise/frame_stream.h"
#include "core/denoise/whitening.h"

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

namespace modestack::app {

/// The names --whiten reports and looks under, for its JSON and its errors.
struct VarianceNames {
    std::string input;                    ///< the shot, for errors
    std::string shot;                     ///< where the whole selection's variance was looked for
    std::vector<std::string> layers;      ///< the selected layers, in order
    std::vector<std::string> layer_shots; ///< where each layer's own variance was looked for
};

/// One part of the shot the rule decides on: the whole selection, or one layer apart.
struct WhitenedPart {
    std::string layer;                                ///< "": the whole selection
    std::optional<denoise::WhiteningWeights> weights; ///< set: whitened by these
    std::string reason; ///< "variance layer", "no variance layer", "off", "off under --transform"
};

/// Decides and computes the weights: one part for one set of modes
/// (settings.layer_channels has fewer than two layers), else one per layer.
/// `mode` is --whiten's auto, on or off. With on, a part without a variance is
/// a bad-input error naming the input and the names looked for.
std::vector<WhitenedPart> choose_whitening(const std::string& mode, bool transformed,
                                           denoise::FrameSource& source, const denoise::Settings& settings,
                                           const VarianceNames& names);

/// Points settings.whitening (one part) or settings.layer_whitening (layers
/// apart) at the weights of `parts`, which must outlive the run.
void apply_whitening(const std::vector<WhitenedPart>& parts, denoise::Settings& settings);

/// The JSON of one part: mode, reason and the weights' figures when whitened.
nlohmann::ordered_json whitened_part_json(const WhitenedPart& part);

/// The method block's "whiten": one part's JSON; for layers apart, mode on,
/// off or "per layer" (some are), the reasons, and "layers" with each part's.
nlohmann::ordered_json whitening_json(const std::vector<WhitenedPart>& parts);

} // namespace modestack::app
