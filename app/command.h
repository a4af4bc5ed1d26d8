// How a subcommand plugs into `modestack`: it adds its options to a CLI11
// sub-app and returns the function main() runs after parsing. Each subcommand
// lives in its own cmd_<name>.cpp and only calls into core/ and io/.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>
#include <limits>
#include <memory>
#include <string>

namespace modestack::app {

/// A whole number of at least 1 (--spp, --max-depth); CLI::PositiveNumber would
/// print "not in range 0 to" the largest double, in full.
inline const CLI::Range kAtLeastOne(1, std::numeric_limits<int>::max(), "at least 1");

/// A registered subcommand.
struct Subcommand {
    CLI::App* cli = nullptr;      ///< its CLI11 sub-app (for "was it chosen?")
    std::function<int()> run;     ///< runs it; returns the exit code
    int usage_exit_code = 2;      ///< exit code for a command-line error in it (compare: 5)
};

/// The whole command line as typed, for provenance attributes and JSON.
const std::string& command_line();
/// Records the command line (main calls it once).
void set_command_line(int argc, char** argv);

Subcommand add_info_command(CLI::App& parent);
Subcommand add_denoise_command(CLI::App& parent);
Subcommand add_render_command(CLI::App& parent);
Subcommand add_refine_command(CLI::App& parent);
Subcommand add_run_command(CLI::App& parent);
Subcommand add_compare_command(CLI::App& parent);

}  // namespace modestack::app
