#pragma once
// The pipeline's flags, made from the library's options table (pipeline/options.h): the tool names no option
// itself. --help lists the Essential tier under its groups; --help-all every option.
#include <CLI/CLI.hpp>

#include <memory>

#include "cli_support.h"
#include "pipeline/options.h"

namespace normalflow::cli {

/// Adds every option of the table that c takes below the Library tier as a flag of cmd, parsing into o (which
/// holds default_options(c): the help shows its values as the defaults), then --config (unless c is Compress)
/// and --json, --quiet into out. A switch on by default is given as --no-NAME.
void add_run_options(CLI::App* cmd, RunOptions& o, Command c, OutputFlags& out);

/// The tool's help formatter: --help leaves out the groups of the Advanced and Expert tiers and says how many
/// options --help-all adds; --help-all lists them all.
std::shared_ptr<CLI::Formatter> tiered_formatter();

}  // namespace normalflow::cli
