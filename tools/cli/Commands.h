// Commands.h - the fluidsurf subcommands. Each registers its options on the CLI11 app and runs
// by turning them into library calls; no file format or algorithm lives here.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>

namespace fluidsurf {
namespace cli {

/// A subcommand's run function, called after parsing; returns the process exit code.
using Runner = std::function<int()>;

Runner addInfoCommand(CLI::App& app);
Runner addConvertCommand(CLI::App& app);
Runner addGenerateCommand(CLI::App& app);
Runner addRasterizeCommand(CLI::App& app);
Runner addMeshCommand(CLI::App& app);
Runner addReconstructCommand(CLI::App& app);
Runner addPostCommand(CLI::App& app);

} // namespace cli
} // namespace fluidsurf
