// normalflow: geometric surface processing via normal maps (Tasdizen et al. 2003).
// Thin command-line front end: each subcommand lives in its own cmd_*.cpp, which parses flags into
// the library's option structs, runs, and maps errors to exit codes (see cli_support.h).
#include <CLI/CLI.hpp>

#include <string>

#include "build_licence.h"
#include "cli_options.h"
#include "commands.h"

int main(int argc, char** argv) {
    using namespace normalflow::cli;
    CLI::App app{"normalflow: geometric surface processing via normal maps (Tasdizen et al. 2003)"};
    app.set_version_flag("--version", version_text());
    app.require_subcommand(1);
    // Subcommands inherit both: --help lists a command's essential options, --help-all every one.
    app.formatter(tiered_formatter());
    app.set_help_all_flag("--help-all", "every option, also those --help leaves out");
    // One line per subcommand (declared in commands.h).
    add_info_command(app);
    add_taubin_command(app);
    add_laplacian_command(app);
    add_bilateral_command(app);
    add_noise_command(app);
    add_compare_command(app);
    add_voxelize_command(app);
    add_extract_command(app);
    add_smooth_command(app);
    add_remesh_command(app);
    add_batch_command(app);
    add_convert_command(app);
    add_compress_command(app);
    add_cleanup_command(app);
    add_tetmesh_command(app);

    install_interrupt_handler();
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e);  // parse errors print usage; RuntimeError carries the command's status
    }
    return 0;
}
