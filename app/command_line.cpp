// The command line as the user typed it, kept for provenance (EXR attributes
// modestack:command and the JSON summaries).
#include "app/command.h"

namespace modestack::app {

namespace {
std::string g_command_line;
}

const std::string& command_line() { return g_command_line; }

void set_command_line(int argc, char** argv)
{
    g_command_line.clear();
    for (int i = 0; i < argc; ++i) {
        if (i)
            g_command_line += ' ';
        std::string argument = argv[i];
        bool quote = argument.empty() || argument.find_first_of(" \t'\"$") != std::string::npos;
        g_command_line += quote ? "'" + argument + "'" : argument;
    }
}

}  // namespace modestack::app
