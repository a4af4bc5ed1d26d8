// What every working subcommand sets up the same way: the thread limit
// (--threads, for TBB and OpenImageIO alike), the progress reporter on stderr
// (--quiet), and the version string for provenance.
#pragma once

#include "core/common/progress.h"

#include <CLI/CLI.hpp>
#include <tbb/global_control.h>

#include <memory>

namespace modestack::app {

/// Options shared by the subcommands that do long work.
struct CommonOptions {
    int threads = 0;     ///< 0 = all cores
    bool quiet = false;  ///< no progress on stderr
};

/// Adds --threads and --quiet to a subcommand.
void add_common_options(CLI::App& command, CommonOptions& options);

/// Applies CommonOptions for the lifetime of the object.
class RunContext {
public:
    explicit RunContext(const CommonOptions& options);
    ~RunContext();
    Progress& progress() { return *m_progress; }

private:
    std::unique_ptr<tbb::global_control> m_thread_limit;
    std::unique_ptr<Progress> m_progress;
};

/// "modestack 0.1.0".
const char* version_string();

}  // namespace modestack::app
