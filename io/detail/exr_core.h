// Internal to io/: what the ZIP reader and writer share around OpenEXR's Core
// API: contexts that report errors to the calling thread instead of stderr,
// and read contexts closed on every path out.
#pragma once

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

}  // namespace modestack::io::detail
