#include "cli_support.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <new>
#include <string>

#include "core/errors.h"

namespace normalflow::cli {

namespace {
std::atomic<bool> g_interrupted{false};
extern "C" void on_signal(int) { g_interrupted.store(true); }
}  // namespace

void install_interrupt_handler() {
    struct sigaction sa {};
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, nullptr);
    sigaction(SIGTERM, &sa, nullptr);
}

bool interrupted() { return g_interrupted.load(); }

TerminalProgress::TerminalProgress(const OutputFlags& f)
    : show_(!f.quiet && !f.json && ::isatty(STDERR_FILENO)), quiet_(f.quiet || f.json) {}

TerminalProgress::~TerminalProgress() { clear_line(); }

void TerminalProgress::clear_line() {
    if (show_ && last_percent_ >= 0) std::fprintf(stderr, "\r\033[K");
    last_percent_ = -1;
}

void TerminalProgress::begin(std::string_view stage) {
    clear_line();
    stage_ = std::string(stage);
    progress(0.0);
}

void TerminalProgress::progress(double fraction) {
    if (!show_) return;
    const int pct = int(fraction * 100.0 + 0.5);
    const auto now = std::chrono::steady_clock::now();
    if (pct == last_percent_ || (now - last_draw_ < std::chrono::milliseconds(100) && pct != 100)) return;
    last_percent_ = pct;
    last_draw_ = now;
    std::fprintf(stderr, "\r\033[K%-12s %3d%%", stage_.c_str(), pct);
    std::fflush(stderr);
}

bool TerminalProgress::should_stop() { return interrupted(); }

void TerminalProgress::note(const std::string& line) const {
    if (quiet_) return;
    std::fprintf(stderr, "%s%s\n", show_ ? "\r\033[K" : "", line.c_str());
}

void refuse_overwriting_input(const std::string& input, const std::string& output) {
    std::error_code ec;
    if (input.empty() || output.empty()) return;
    if (input == output || std::filesystem::equivalent(input, output, ec))
        throw InvalidInput(output + " is the input file; write the result to another file");
}

void refuse_unwritable_output(const std::string& output) {
    if (output.empty()) return;
    namespace fs = std::filesystem;
    std::error_code ec;
    const fs::path out(output);
    if (fs::is_directory(out, ec)) throw IoError(output + " cannot be written: it is a folder; name a file in it");
    const fs::path folder = out.has_parent_path() ? out.parent_path() : fs::path(".");
    const auto status = fs::status(folder, ec);
    if (!fs::exists(status))
        throw IoError(output + " cannot be written: the folder " + folder.string() + " does not exist");
    if (!fs::is_directory(status))
        throw IoError(output + " cannot be written: " + folder.string() + " is not a folder");
    if (::access(folder.c_str(), W_OK | X_OK) != 0)
        throw IoError(output + " cannot be written: the folder " + folder.string() + " is not writable");
}

ErrorStatus error_status(std::exception_ptr error) {
    try {
        std::rethrow_exception(error);
    } catch (const Cancelled& e) {
        return {130, "cancelled"};
    } catch (const InvalidInput& e) {
        return {3, e.what()};
    } catch (const IoError& e) {
        return {4, e.what()};
    } catch (const NumericalError& e) {
        return {5, std::string("numerical error: ") + e.what()};
    } catch (const OutOfMemory& e) {
        return {6, e.what()};
    } catch (const std::bad_alloc&) {
        return {6, "out of memory"};
    } catch (const std::exception& e) {
        return {1, e.what()};
    }
}

int guarded(const char* command, int (*fn)(void*), void* ctx) {
    try {
        return fn(ctx);
    } catch (...) {
        const ErrorStatus e = error_status(std::current_exception());
        std::fprintf(stderr, "normalflow %s: %s\n", command, e.message.c_str());
        return e.status;
    }
}

void add_output_flags(CLI::App* cmd, OutputFlags& out) {
    cmd->add_flag("--json", out.json, "print one JSON object on the last line of standard output");
    cmd->add_flag("-q,--quiet", out.quiet, "print nothing but errors");
}

std::vector<std::string> attribute_names(const Mesh& m) {
    std::vector<std::string> out;
    if (m.has_normals()) out.emplace_back("normals");
    if (m.has_colors()) out.emplace_back("colors");
    if (m.has_texcoords()) out.emplace_back("texcoords");
    return out;
}

std::string attribute_words(const Mesh& m) {
    std::string out;
    const auto add = [&](bool has, const char* word) {
        if (has) out += (out.empty() ? "" : ", ") + std::string(word);
    };
    add(m.has_normals(), "normals");
    add(m.has_colors(), "colours");
    add(m.has_texcoords(), "texture coordinates");
    return out.empty() ? "none" : out;
}

void add_config_option(CLI::App* cmd) {
    cmd->add_option("--config",
                    "read flags from a TOML or INI file: one `name = value` per line, names as the long "
                    "flags (mode = \"isotropic\", target-faces = 20000, repair = false); flags given "
                    "here win")
        ->type_name("FILE");
}

void apply_config_file(CLI::App* cmd) {
    const CLI::Option* config = cmd->get_option_no_throw("--config");
    if (!config || config->count() == 0) return;
    const std::string file = config->as<std::string>();
    std::vector<CLI::ConfigItem> items;
    {
        std::ifstream in(file);
        if (!in) throw IoError(file + ": cannot read the config file");
        try {
            items = CLI::ConfigTOML().from_config(in);
        } catch (const CLI::Error& e) {
            throw InvalidInput(file + ": " + e.what());
        }
    }
    for (const CLI::ConfigItem& item : items) {
        if (item.name == "++" || item.name == "--") continue;  // a section's start and end
        if (!item.parents.empty() && !(item.parents.size() == 1 && item.parents[0] == cmd->get_name()))
            throw InvalidInput(file + ": [" + item.parents[0] + "]: only the [" + cmd->get_name() +
                               "] section applies here");
        std::string name = item.name;  // target_faces as target-faces: a report's "parameters" keys
        std::replace(name.begin(), name.end(), '_', '-');
        std::vector<std::string> inputs = item.inputs;
        CLI::Option* op = cmd->get_option_no_throw("--" + name);
        if (!op && inputs.size() == 1 && (inputs[0] == "true" || inputs[0] == "false") &&
            (op = cmd->get_option_no_throw("--no-" + name))) {  // repair = false is --no-repair
            name = "no-" + name;
            inputs[0] = inputs[0] == "true" ? "false" : "true";
        }
        if (!op || op == config) throw InvalidInput(file + ": " + item.name + ": not a flag of " + cmd->get_name());
        if (op->count() > 0) continue;  // given on the command line
        try {
            for (std::string& in : inputs) in = op->get_flag_value(name, in);  // a flag's value (inverted for !--no-x)
            op->add_result(inputs);
            op->run_callback();
        } catch (const CLI::Error& e) {
            throw InvalidInput(file + ": " + item.name + ": " + e.what());
        }
    }
}

CLI::Option* add_decimator_option(CLI::App* cmd, Decimator& target) {
    const std::map<std::string, Decimator> names = {{"auto", Decimator::Auto},
                                                    {"quadric", Decimator::Quadric},
                                                    {"meshoptimizer", Decimator::Meshoptimizer},
                                                    {"cgal", Decimator::Cgal}};
    return add_enum_option(cmd, "--decimator", target, names,
                           "auto: normalflow's quadric edge collapse, checked (closed, manifold, no "
                           "self-intersections), CGAL's edge collapse where a check fails; quadric: that alone; "
                           "meshoptimizer: meshoptimizer's simplifier (fast, may leave the surface non-manifold "
                           "or self-intersecting); cgal: CGAL's edge collapse (slower, GPL)");
}

}  // namespace normalflow::cli
