// normalflow: geometric surface processing via normal maps (Tasdizen et al. 2003).
// Thin command-line front end: parse flags into the library's option structs, run, map errors to exit codes.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <string>

#include "commands.h"
#include "core/version.h"

namespace {
using namespace normalflow::cli;

void add_output_flags(CLI::App* cmd, OutputFlags& out) {
    cmd->add_flag("--json", out.json, "print one JSON object on the last line of standard output");
    cmd->add_flag("-q,--quiet", out.quiet, "print nothing but errors");
}

template <class Args>
int dispatch(const char* name, int (*run)(const Args&), const Args& args) {
    struct Ctx { int (*run)(const Args&); const Args* args; } ctx{run, &args};
    return guarded(name, [](void* p) { auto* c = static_cast<Ctx*>(p); return c->run(*c->args); }, &ctx);
}
}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"normalflow: geometric surface processing via normal maps (Tasdizen et al. 2003)"};
    app.set_version_flag("--version", std::string("normalflow ") + normalflow::version());
    app.require_subcommand(1);

    InfoArgs info;
    auto* c_info = app.add_subcommand("info", "report what a mesh file holds: counts, defects, topology");
    c_info->add_option("IN", info.input, "mesh file (obj, ply, off, stl, gltf, glb, drc)")->required();
    c_info->add_flag("--self-intersections", info.self_intersections, "also count intersecting triangle pairs (slower)");
    add_output_flags(c_info, info.out);

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e);
    }
    install_interrupt_handler();
    if (*c_info) return dispatch("info", run_info, info);
    return 1;
}
