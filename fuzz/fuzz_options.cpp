// Fuzz harness: the command line. The input is one argument per line; they are
// parsed by the same CLI11 app main() builds (every subcommand, no command is
// run), and each argument also goes through the value parsers CLI11 does not
// know (memory and image sizes, frame ranges). Every rejection must be a
// CLI11 parse error or a modestack::Error; accepted values must be in range.
#include "app/command.h"
#include "app/option_values.h"
#include "core/common/error.h"
#include "io/sequence.h"

#include <CLI/CLI.hpp>

#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

namespace {

constexpr std::size_t kMaxArguments = 64;

void check(bool condition)
{
    if (!condition)
        std::abort();
}

void parse_values(const std::string& argument)
{
    using modestack::Error;
    try {
        check(modestack::app::parse_memory_size(argument, "--max-memory") > 0);
    } catch (const Error&) {
    }
    try {
        int width = 0, height = 0;
        modestack::app::parse_image_size(argument, width, height);
        check(width >= 1 && width <= 65536 && height >= 1 && height <= 65536);
    } catch (const Error&) {
    }
    try {
        check(!modestack::io::parse_frame_range(argument).empty());
    } catch (const Error&) {
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    std::vector<std::string> arguments{"modestack"};
    std::string current;
    for (std::size_t i = 0; i < size && arguments.size() < kMaxArguments; ++i) {
        if (data[i] == '\n') {
            arguments.push_back(current);
            current.clear();
        } else {
            current.push_back(static_cast<char>(data[i]));
        }
    }
    if (!current.empty() && arguments.size() < kMaxArguments)
        arguments.push_back(current);

    CLI::App cli{"modestack", "modestack"};
    cli.set_version_flag("--version", "modestack fuzz");
    cli.require_subcommand(1);
    cli.option_defaults()->always_capture_default();
    std::vector<modestack::app::Subcommand> subcommands{
        modestack::app::add_info_command(cli),   modestack::app::add_render_command(cli),
        modestack::app::add_refine_command(cli), modestack::app::add_run_command(cli),
        modestack::app::add_denoise_command(cli), modestack::app::add_compare_command(cli)};
    std::vector<char*> argv;
    for (std::string& argument : arguments)
        argv.push_back(argument.data());
    try {
        cli.parse(static_cast<int>(argv.size()), argv.data());
    } catch (const CLI::ParseError&) {
    }
    for (std::size_t i = 1; i < arguments.size(); ++i)
        parse_values(arguments[i]);
    return 0;
}
