// How a copied output frame is encoded and which of its input's channels it
// holds (--compression, --data-type, --only-denoised), and the one rule for
// which compression an output (each part of a multi-part output) gets: the one
// asked for, else the input's when it is lossless, else ZIP, so that nothing
// passed through is ever degraded by a lossy re-encode (docs/design.md, "File
// formats"). Compression names are OpenEXR's as OpenImageIO and oiiotool spell them.
#pragma once

#include <string>
#include <vector>

namespace modestack::io {

/// The pixel type of the channels an output writes anew (replaced and added).
enum class WrittenType {
    AsInput, ///< each replaced channel's own; added channels the first selected channel's
    Half,
    Float,
};

/// How a copied output is written (FrameOutput); the default copies everything as today.
struct OutputFormat {
    /// --compression: a name is_compression_name accepts; "" = the rule's default (output_compression).
    std::string compression;
    WrittenType written_type = WrittenType::AsInput; ///< --data-type
    /// --only-denoised: keep only the replaced channels, the layers `kept_layers` and the added channels.
    bool only_written = false;
    /// Layers rewritten in the copied rows (the beauty under --update-beauty), by their
    /// name in the frame as one image ("" = the bare R, G, B, A): kept whole, alpha
    /// too, by `only_written`.
    std::vector<std::string> kept_layers;
};

/// "none, rle, zips, zip, piz, pxr24, b44, b44a, dwaa, dwab": for messages and --help.
const char* compression_names();
/// Whether `name` is one of compression_names(), or dwaa/dwab with a quality level
/// ("dwaa:45", a number above 0).
bool is_compression_name(const std::string& name);
/// Whether a compression (as OpenImageIO names an input's) keeps every value:
/// none, rle, zips, zip, piz. Lossy (pxr24, b44, b44a, dwaa, dwab) or unknown: false.
bool is_lossless_compression(const std::string& compression);
/// The compression an output part gets: `requested` when given (a lossy one
/// too: the user asked), else the input part's `input_compression` when it is
/// lossless, else "zip".
std::string output_compression(const std::string& requested, const std::string& input_compression);

/// A compression name split into its method and DWA quality level ("dwaa:45" is
/// {"dwaa", 45}); the level is negative when the name gives none.
struct CompressionName {
    std::string method;
    float dwa_level = -1.0f;
};
CompressionName split_compression(const std::string& name);

} // namespace modestack::io
