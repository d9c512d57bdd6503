// The headless `drape` command: dispatches to the registered sub-commands.
#include "cli/command.hpp"

#include "engine/core/error.hpp"

#include <cstdio>
#include <exception>
#include <iostream>

namespace {
void print_overview()
{
    std::cout << "usage: drape COMMAND [ARGS]\n\ncommands:\n";
    for (const auto& [name, c] : drape::cli::registry())
        std::printf("  %-12s %s\n", name.c_str(), c.summary.c_str());
    std::cout << "\n`drape help COMMAND` shows a command's flags.\n";
}
} // namespace

int main(int argc, char** argv)
{
    using namespace drape::cli;
    std::vector<std::string> args(argv + 1, argv + argc);
    if (args.empty() || args[0] == "--help" || args[0] == "-h") {
        print_overview();
        return args.empty() ? 2 : 0;
    }
    if (args[0] == "help") {
        if (args.size() > 1) {
            auto it = registry().find(args[1]);
            if (it == registry().end()) {
                std::cerr << "drape: unknown command '" << args[1] << "'\n";
                return 2;
            }
            std::cout << it->second.usage << "\n";
            return 0;
        }
        print_overview();
        return 0;
    }
    auto it = registry().find(args[0]);
    if (it == registry().end()) {
        std::cerr << "drape: unknown command '" << args[0] << "' (see `drape --help`)\n";
        return 2;
    }
    std::vector<std::string> rest(args.begin() + 1, args.end());
    for (const auto& a : rest)
        if (a == "--help" || a == "-h") {
            std::cout << it->second.usage << "\n";
            return 0;
        }
    try {
        return it->second.run(rest);
    } catch (const UsageError& e) {
        std::cerr << "drape " << args[0] << ": " << e.what() << "\n\n" << it->second.usage << "\n";
        return 2;
    } catch (const drape::Error& e) {
        std::cerr << "drape " << args[0] << ": error: " << e.what() << "\n";
        return 1;
    } catch (const std::exception& e) {
        std::cerr << "drape " << args[0] << ": internal error: " << e.what() << "\n";
        return 3;
    }
}
