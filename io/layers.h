// Channel layers and the `--layer NAME` selection rule. A channel name splits at
// its last dot into a layer and a component (`ViewLayer.DiffInd.R` → layer
// `ViewLayer.DiffInd`, component `R`; a bare `R` has the unnamed layer ""). A
// layer selector NAME matches the layer `NAME` itself or any layer ending in
// `.NAME`, so `--layer DiffInd` finds Cycles' `ViewLayer.DiffInd.*`, and
// `--layer diffuse_indirect` Arnold's `diffuse_indirect.*`; when no layer
// matches, NAME may be a bare channel other than R, G, B, A (Arnold's depth `Z`),
// which is then a layer of one channel named NAME.
#pragma once

#include <string>
#include <vector>

namespace modestack::io {

/// The channels of one layer, in file order.
struct ChannelLayer {
    std::string name;                     ///< "" for bare R, G, B, A
    std::vector<int> channel_indices;     ///< indices into the image's channel list
    std::vector<std::string> components;  ///< "R", "G", "B", "X", ...
};

/// A layer chosen for denoising: which channels, and the names of its sigma channels.
struct SelectedLayer {
    std::string name;                        ///< full layer name, e.g. "ViewLayer.DiffInd"
    std::vector<int> channel_indices;        ///< the channels denoised (alpha excluded)
    std::vector<std::string> channel_names;  ///< their full names
    std::vector<std::string> sigma_names;    ///< "<layer>.sigma.<component>" per channel
};

/// The names the channels of a part named `part_name` have when a multi-part
/// file is read as one image (the one rule, for the readers and `info`): a part
/// with a bare channel (`R`, as Arnold, Karma and Nuke write a part per layer)
/// puts every channel in the layer its name makes (`R` and `sigma.R` of part
/// `diffuse` are `diffuse.R`, `diffuse.sigma.R`), as OIIO's and Nuke's readers
/// present such parts; a part whose channels all carry a layer, or a part
/// without a name, keeps them as they are.
std::vector<std::string> part_channel_names(const std::string& part_name,
                                            const std::vector<std::string>& channels);

/// Splits a channel name into layer and component at the last dot.
void split_channel_name(const std::string& channel, std::string& layer, std::string& component);

/// Groups channel names by layer, layers in order of first appearance.
std::vector<ChannelLayer> group_layers(const std::vector<std::string>& channel_names);

/// Human-readable layer list for error messages: "(default) [R,G,B,A], ViewLayer.DiffInd [R,G,B]".
std::string describe_layers(const std::vector<ChannelLayer>& layers);

/// Resolves `--layer` selectors against a file's channels. With no selector,
/// the only layer holding R, G and B is chosen. Throws Error naming `file` when
/// a selector matches nothing or several layers, or when no default exists.
std::vector<SelectedLayer> select_layers(const std::vector<std::string>& channel_names,
                                         const std::vector<std::string>& selectors, const std::string& file);

}  // namespace modestack::io
