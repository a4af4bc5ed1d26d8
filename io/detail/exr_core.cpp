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

}  // namespace modestack::io::detail
