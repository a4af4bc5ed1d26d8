#include "app/run_context.h"

#include "io/text_output.h"

#include <tbb/global_control.h>

#include <unistd.h>

namespace modestack::app {

void add_common_options(CLI::App& command, CommonOptions& options)
{
    command.add_option("--threads", options.threads, "Worker threads (0 = all cores); results do not depend on it")
        ->check(CLI::NonNegativeNumber);
    command.add_flag("-q,--quiet", options.quiet, "No progress on stderr (warnings and errors still print)");
}

RunContext::RunContext(const CommonOptions& options)
{
    if (options.threads > 0)
        m_thread_limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                               static_cast<size_t>(options.threads));
    io::set_io_threads(options.threads);
    m_progress = std::make_unique<Progress>(stderr, options.quiet, isatty(fileno(stderr)) != 0);
}

RunContext::~RunContext() = default;

const char* version_string() { return "modestack " MODESTACK_VERSION; }

}  // namespace modestack::app
