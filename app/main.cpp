// modestack: the command. Parses the subcommand and its options, runs it, and
// maps every failure to one line on stderr and a documented exit code:
// 0 ok, 1 bad input or failed run, 2 bad usage, 3 internal error,
// 128 + signal when interrupted (compare has its own idiff-style codes).
#include "app/command.h"
#include "app/run_context.h"
#include "core/common/error.h"
#include "core/common/progress.h"

#include <CLI/CLI.hpp>

#include <csignal>
#include <cstdio>
#include <exception>
#include <regex>
#include <sys/resource.h>
#include <vector>

namespace {

using namespace modestack;

void on_signal(int signal_number)
{
    // A second signal means "stop now": restore the default and re-raise.
    if (cancel_requested()) {
        std::signal(signal_number, SIG_DFL);
        std::raise(signal_number);
    }
    request_cancel_by_signal(signal_number);
}

// A shot keeps one input and one output file open per frame; allow as many
// descriptors as the system lets us.
void raise_open_file_limit()
{
    rlimit limit{};
    if (getrlimit(RLIMIT_NOFILE, &limit) == 0 && limit.rlim_cur < limit.rlim_max) {
        limit.rlim_cur = limit.rlim_max;
        setrlimit(RLIMIT_NOFILE, &limit);
    }
}

// CLI11's PositiveNumber and NonNegativeNumber checks print the largest double
// in full (309 digits) as their upper bound: keep the message readable.
std::string shorten_huge_numbers(const std::string& message)
{
    static const std::regex huge("17976931348623157[0-9]{292}(\\.0+)?");
    return std::regex_replace(message, huge, "1.8e308");
}

int report(const std::string& message, int code)
{
    std::fprintf(stderr, "modestack: %s\n", message.c_str());
    return code;
}

}  // namespace

int main(int argc, char** argv)
{
    app::set_command_line(argc, argv);
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    raise_open_file_limit();

    CLI::App cli{"modestack: temporal low-rank denoising of rendered EXR sequences", "modestack"};
    cli.set_version_flag("--version", app::version_string());
    cli.require_subcommand(1);
    cli.option_defaults()->always_capture_default();
    cli.footer("Exit codes: 0 ok, 1 bad input or failed run, 2 bad usage, 3 internal error, 130/143 interrupted.\n"
               "See modestack(1) for every option.");

    std::vector<app::Subcommand> subcommands;
    subcommands.push_back(app::add_info_command(cli));
    subcommands.push_back(app::add_render_command(cli));
    subcommands.push_back(app::add_refine_command(cli));
    subcommands.push_back(app::add_run_command(cli));
    subcommands.push_back(app::add_denoise_command(cli));
    subcommands.push_back(app::add_compare_command(cli));

    try {
        cli.parse(argc, argv);
    } catch (const CLI::CallForHelp& help) {
        return cli.exit(help);
    } catch (const CLI::CallForAllHelp& help) {
        return cli.exit(help);
    } catch (const CLI::CallForVersion& version) {
        return cli.exit(version);
    } catch (const CLI::ParseError& error) {
        int code = exit_code(ErrorKind::Usage);
        for (const auto& subcommand : subcommands)
            if (subcommand.cli->parsed())
                code = subcommand.usage_exit_code;
        return report(shorten_huge_numbers(error.what()) + " (run 'modestack --help')", code);
    }

    try {
        for (auto& subcommand : subcommands)
            if (subcommand.cli->parsed())
                return subcommand.run();
        return report("no subcommand given (run 'modestack --help')", exit_code(ErrorKind::Usage));
    } catch (const Error& error) {
        if (error.kind() == ErrorKind::Cancelled && cancel_signal() != 0)
            return report(error.what(), 128 + cancel_signal());
        return report(error.what(), exit_code(error.kind()));
    } catch (const std::bad_alloc&) {
        return report("out of memory (try a smaller --max-memory)", exit_code(ErrorKind::BadInput));
    } catch (const std::exception& error) {
        return report(std::string("internal error: ") + error.what(), exit_code(ErrorKind::Internal));
    }
}
