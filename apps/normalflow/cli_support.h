#pragma once
// Shared plumbing of the normalflow subcommands: terminal progress, Ctrl-C, JSON output, exit codes.
#include <CLI/CLI.hpp>

#include <chrono>
#include <exception>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "core/progress.h"
#include "core/stopwatch.h"
#include "io/util/json.h"
#include "pipeline/pipeline.h"       // Decimator
#include "pipeline/system_memory.h"  // peak_memory_bytes, available_memory_bytes, format_bytes

namespace normalflow::cli {

/// Output switches every subcommand takes.
struct OutputFlags {
    bool json = false;   ///< one JSON object on the last line of stdout
    bool quiet = false;  ///< nothing but errors
};

/// Progress on stderr (only when stderr is a terminal and not quiet/json); stops on SIGINT.
class TerminalProgress : public Progress {
public:
    explicit TerminalProgress(const OutputFlags& f);
    ~TerminalProgress() override;
    void begin(std::string_view stage) override;
    void progress(double fraction) override;
    bool should_stop() override;
    /// A line of information for the user (stderr; suppressed by --quiet and --json).
    void note(const std::string& line) const;

private:
    bool show_;
    bool quiet_;
    std::string stage_;
    int last_percent_ = -1;
    std::chrono::steady_clock::time_point last_draw_{};
    void clear_line();
};

/// Installs the SIGINT/SIGTERM handler that makes should_stop() true.
void install_interrupt_handler();
bool interrupted();

/// The per-vertex attributes m has, as JSON names ("normals", "colors", "texcoords") and as words for a
/// text line ("normals, colours, texture coordinates"; "none").
std::vector<std::string> attribute_names(const Mesh& m);
std::string attribute_words(const Mesh& m);

/// An exception of normalflow's as an exit status and a one-line message (guarded() prints it after the command).
struct ErrorStatus {
    int status;  ///< 1 other error, 3 invalid input, 4 I/O error, 5 numerical error, 6 out of memory, 130 cancelled
    std::string message;
};
ErrorStatus error_status(std::exception_ptr error);

/// Runs fn, mapping normalflow's exceptions to one line on stderr and an exit status:
/// 0 ok, 1 other error, 3 invalid input, 4 I/O error, 5 numerical error, 6 out of memory, 130 cancelled.
int guarded(const char* command, int (*fn)(void*), void* ctx);

/// Nothing the user had is overwritten: an output that is the input file itself (the same path, or a link
/// to it) is refused before any work.
/// \throw InvalidInput "OUT is the input file; write the result to another file" (guarded() names the command).
void refuse_overwriting_input(const std::string& input, const std::string& output);

/// No work is thrown away: an output whose folder does not exist, is not a folder or cannot be written to, or
/// that is itself a folder, is refused before any work (the result is written to a temporary file in that folder
/// and renamed into place).
/// \throw IoError "OUT cannot be written: ..." naming the folder and why.
void refuse_unwritable_output(const std::string& output);

/// Adds --json and --quiet to a subcommand.
void add_output_flags(CLI::App* cmd, OutputFlags& out);

/// The name of `value` in `names` (the command line's spelling of an enum value).
template <class E>
std::string name_of(const std::map<std::string, E>& names, E value) {
    for (const auto& [name, v] : names)
        if (v == value) return name;
    return "?";
}

/// Adds an option that parses one of `names` straight into the enum `target`; the help shows the
/// names and the default (target's value when the option is added: the library's default).
template <class E>
CLI::Option* add_enum_option(CLI::App* cmd, const std::string& flag, E& target, const std::map<std::string, E>& names,
                             const std::string& help) {
    std::string choices;
    for (const auto& [name, v] : names) choices += (choices.empty() ? "" : "|") + name;
    CLI::Validator parse = CLI::CheckedTransformer(names);
    parse.description("");
    return cmd->add_option(flag, target, help)
        ->transform(parse)
        ->type_name(choices)
        ->default_str(name_of(names, target));
}

/// Adds --decimator auto|quadric|meshoptimizer|cgal (what --target-faces runs, decimate_mesh).
CLI::Option* add_decimator_option(CLI::App* cmd, Decimator& target);

/// --config FILE: the command's flags from a TOML or INI file (`name = value`, names as the long flags without
/// dashes); flags given on the command line win. Applied by on_run (apply_config_file) before the command runs.
void add_config_option(CLI::App* cmd);

/// Sets every option of cmd that the command line left unset and --config's file names, through the option's own
/// checks. Nothing when cmd has no --config or it was not given.
/// \throw InvalidInput naming the file and the key: an unknown key, a bad value, a section other than cmd's.
/// \throw IoError when the file cannot be read.
void apply_config_file(CLI::App* cmd);

/// Makes cmd run fn(*args) under guarded() once parsed; the exit status reaches main() as a
/// CLI::RuntimeError, which CLI::App::exit returns without printing.
template <class Args>
void on_run(CLI::App* cmd, std::shared_ptr<Args> args, int (*fn)(const Args&)) {
    cmd->final_callback([cmd, args, fn] {
        struct Ctx {
            int (*fn)(const Args&);
            const Args* args;
            CLI::App* cmd;
        } ctx{fn, args.get(), cmd};
        const int status = guarded(
            cmd->get_name().c_str(),
            [](void* p) {
                auto* c = static_cast<Ctx*>(p);
                apply_config_file(c->cmd);
                if constexpr (requires {
                                  c->args->input;
                                  c->args->output;
                              }) {
                    refuse_overwriting_input(c->args->input, c->args->output);
                    refuse_unwritable_output(c->args->output);
                }
                return c->fn(*c->args);
            },
            &ctx);
        throw CLI::RuntimeError(status);
    });
}

}  // namespace normalflow::cli
