// Internal to io/: what the ZIP reader and writer share around OpenEXR's Core
// API: contexts that report errors to the calling thread instead of stderr,
// and read contexts closed on every path out.
#pragma once

#include <OpenImageIO/imageio.h>
#include <openexr.h>

#include <string>

namespace modestack::io::detail {

/// A context initializer whose error messages are kept for last_core_message().
exr_context_initializer_t core_initializer();

/// The last message OpenEXR's Core reported on this thread ("" after clearing).
const std::string& last_core_message();
void clear_core_message();

/// A file opened for reading with the Core API; `context` is null when it could
/// not be opened (last_core_message() says why). A damaged offset table is an
/// error, as in OpenImageIO's reader, not rebuilt.
struct CoreReadContext {
    exr_context_t context = nullptr;
    explicit CoreReadContext(const std::string& file);
    ~CoreReadContext();
    CoreReadContext(const CoreReadContext&) = delete;
    CoreReadContext& operator=(const CoreReadContext&) = delete;
};

/// What the ZIP reader and writer read of a part they can handle exactly: a
/// scanline part, ZIP or ZIPS, no subsampled channel, and the data window and
/// channel count OpenImageIO reports in its spec.
struct ZipPart {
    exr_compression_t compression = EXR_COMPRESSION_ZIP;
    exr_attr_box2i_t data_window{};
    const exr_attr_chlist_t* channels = nullptr;  ///< owned by the context
    int lines_per_chunk() const { return compression == EXR_COMPRESSION_ZIP ? 16 : 1; }
};

/// Fills `part` from part `part_index` of `context` (a part whose OpenImageIO
/// spec is `spec`); false when it is not such a part (the caller then uses
/// OpenImageIO).
bool read_zip_part(exr_const_context_t context, int part_index, const OIIO::ImageSpec& spec, ZipPart& part);

}  // namespace modestack::io::detail
