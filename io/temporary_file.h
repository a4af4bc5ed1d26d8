// The temporary files every output is written under before it is renamed into
// place (docs/robustness.md), and the clean-up of those a killed run left
// behind. A temporary is `.<final name>.<host>.<pid>-<n>.modestack-tmp` in the
// final file's directory: hidden, never matching an output pattern, unique per
// process and output. A run that writes into a directory first removes the
// temporaries there of processes of this host that no longer exist (SIGKILL, a
// crash, a power cut); other hosts' are left alone, since their pids mean
// nothing here, and so are those of live processes (a concurrent run).
#pragma once

#include <string>

namespace modestack::io {

/// A fresh temporary path next to `final_path`, unique within this process.
std::string temporary_path_for(const std::string& final_path);

/// Removes, once per directory per process, the temporaries in the directory of
/// `final_path` whose process ran on this host and is gone. Returns how many it
/// removed (0 when the directory was already cleaned by this process).
int remove_stale_temporaries(const std::string& final_path);

}  // namespace modestack::io
