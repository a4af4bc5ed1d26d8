#include "io/detail/exr_core.h"

namespace modestack::io::detail {
namespace {

// Each reader's and writer's calls all run on the thread that makes them.
thread_local std::string t_core_message;

void remember_message(exr_const_context_t, exr_result_t, const char* message)
{
    t_core_message = message ? message : "";
}

}  // namespace

exr_context_initializer_t core_initializer()
{
    exr_context_initializer_t initializer = EXR_DEFAULT_CONTEXT_INITIALIZER;
    initializer.error_handler_fn = &remember_message;
    return initializer;
}

const std::string& last_core_message() { return t_core_message; }

void clear_core_message() { t_core_message.clear(); }

CoreReadContext::CoreReadContext(const std::string& file)
{
    exr_context_initializer_t initializer = core_initializer();
    initializer.flags |= EXR_CONTEXT_FLAG_DISABLE_CHUNK_RECONSTRUCTION;
    if (exr_start_read(&context, file.c_str(), &initializer) != EXR_ERR_SUCCESS)
        context = nullptr;
}

CoreReadContext::~CoreReadContext()
{
    if (context)
        exr_finish(&context);
}

bool read_zip_part(exr_const_context_t context, int part_index, const OIIO::ImageSpec& spec, ZipPart& part)
{
    if (spec.tile_width != 0 || spec.depth > 1 || spec.deep)
        return false;
    int parts = 0;
    exr_storage_t storage = EXR_STORAGE_LAST_TYPE;
    if (exr_get_count(context, &parts) != EXR_ERR_SUCCESS || part_index < 0 || part_index >= parts ||
        exr_get_storage(context, part_index, &storage) != EXR_ERR_SUCCESS ||
        storage != EXR_STORAGE_SCANLINE ||
        exr_get_compression(context, part_index, &part.compression) != EXR_ERR_SUCCESS ||
        (part.compression != EXR_COMPRESSION_ZIP && part.compression != EXR_COMPRESSION_ZIPS) ||
        exr_get_channels(context, part_index, &part.channels) != EXR_ERR_SUCCESS ||
        exr_get_data_window(context, part_index, &part.data_window) != EXR_ERR_SUCCESS)
        return false;
    const exr_attr_box2i_t& window = part.data_window;
    if (window.max.x - window.min.x + 1 != spec.width || window.max.y - window.min.y + 1 != spec.height ||
        window.min.x != spec.x || window.min.y != spec.y || part.channels->num_channels != spec.nchannels)
        return false;
    for (int c = 0; c < part.channels->num_channels; ++c)
        if (part.channels->entries[c].x_sampling != 1 || part.channels->entries[c].y_sampling != 1)
            return false;
    return true;
}

}  // namespace modestack::io::detail
