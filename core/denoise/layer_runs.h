// Several layers denoised in one run, each on its own temporal modes and N
// (Settings::layer_channels; docs/design.md, "Several layers"): a diffuse and a
// glossy layer light the shot differently, so modes shared between them fit
// neither. Every layer runs the passes of passes.h on a view of the source that
// holds only its channels, and the layers' passes advance band by band
// together: the first layer's read of a band decodes every layer's channels of
// it and keeps them until the other layers have read theirs (SharedRows), and
// each output frame is written once a band, when every layer has rebuilt its
// rows of it (LayerCombiner). So the files are decoded and written as often as
// in a run of one layer, and each layer's result has the bits of a run of that
// layer alone.
#pragma once

#include "core/denoise/engine.h"

#include <vector>

namespace modestack::denoise {

/// Runs every layer of settings.layer_channels (at least two) on its own modes,
/// interleaved band by band; one report per layer, in order. The randomized
/// SVD's passes cannot interleave: with it each layer runs its own reads.
std::vector<Report> run_layers(FrameSource& source, FrameSink& sink, const Settings& settings,
                               Progress& progress);

/// One report for the whole run: the first layer's, with the shot's channels,
/// the counts of every layer added up, the run's `seconds` per phase and the
/// layers' own reports in Report::layers.
Report merge_layer_reports(std::vector<Report> layers, const ShotShape& shape);

} // namespace modestack::denoise
