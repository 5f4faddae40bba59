// The pipeline's flags from the options table (cli_options.h).
#include "cli_options.h"

#include <string>

#include "core/errors.h"

namespace normalflow::cli {

namespace {

/// The heading suffix of the groups --help leaves out.
constexpr std::string_view kMore = " (more)";

bool ends_with_more(const std::string& group) {
    return group.size() >= kMore.size() && group.compare(group.size() - kMore.size(), kMore.size(), kMore) == 0;
}

class TieredFormatter : public CLI::Formatter {
public:
    std::string make_help(const CLI::App* app, std::string name, CLI::AppFormatMode mode) const override {
        all_ = mode != CLI::AppFormatMode::Normal;
        std::string out = CLI::Formatter::make_help(app, name, mode);
        for (std::size_t at; (at = out.find("\n\n\n")) != std::string::npos;) out.erase(at, 1);  // left out groups
        if (all_) return out;
        std::size_t more = 0;
        for (const CLI::Option* o : app->get_options())
            if (ends_with_more(o->get_group())) ++more;
        if (more > 0) out += std::to_string(more) + " more options: --help-all\n";
        return out;
    }
    std::string make_group(std::string group, bool positional, std::vector<const CLI::Option*> opts) const override {
        if (!all_ && ends_with_more(group)) return "";
        return CLI::Formatter::make_group(std::move(group), positional, std::move(opts));
    }

    /// "--no-repair", not CLI11's "--no-repair{false}".
    std::string make_option_name(const CLI::Option* opt, bool positional) const override {
        std::string name = CLI::Formatter::make_option_name(opt, positional);
        const std::size_t brace = name.find('{');
        return brace == std::string::npos ? name : name.erase(brace, name.find('}', brace) + 1 - brace);
    }

private:
    mutable bool all_ = false;
};

std::string type_name(const OptionSpec& s) {
    switch (s.kind) {
        case OptionKind::Choice: {
            std::string names;
            for (const OptionChoice& c : s.choices) names += (names.empty() ? "" : "|") + c.name;
            return names;
        }
        case OptionKind::Int:
        case OptionKind::Count: return s.zero.empty() ? "INT" : "INT|" + s.zero;
        case OptionKind::Bytes: return "SIZE|" + s.zero;
        case OptionKind::OptionalReal: return "V";
        default: return s.zero.empty() ? "FLOAT" : "FLOAT|" + s.zero;
    }
}

}  // namespace

std::shared_ptr<CLI::Formatter> tiered_formatter() { return std::make_shared<TieredFormatter>(); }

void add_run_options(CLI::App* cmd, RunOptions& o, Command c, OutputFlags& out) {
    if (const CLI::Option* all = cmd->get_help_all_ptr()) const_cast<CLI::Option*>(all)->group("");  // in the footer
    const auto add = [&](const OptionSpec* s) {
        std::string group = to_string(s->group);
        if (s->tier != Tier::Essential && c != Command::Compress) group += kMore;
        CLI::Option* op = nullptr;
        if (s->kind == OptionKind::Switch) {
            bool& on = *static_cast<bool*>(s->ref(o));
            op = on ? cmd->add_flag("!--no-" + s->name, on, "turn off: " + s->help)
                    : cmd->add_flag("--" + s->name, on, s->help);
        } else {
            op = cmd->add_option_function<std::string>(
                "--" + s->name, [s, &o](const std::string& text) { set_option(*s, o, text); }, s->help);
            op->check(CLI::Validator(
                [s](std::string& text) {
                    RunOptions scratch;
                    try {
                        set_option(*s, scratch, text);
                        return std::string();
                    } catch (const InvalidInput& e) {
                        return std::string(e.what());
                    }
                },
                ""));
            op->type_name(type_name(*s));
            if (s->kind != OptionKind::OptionalReal) op->default_str(option_text(*s, o));
        }
        op->group(group);
    };
    // --help-all lists --help's options first, then the rest
    for (const OptionSpec* s : user_options(c))
        if (s->tier == Tier::Essential || c == Command::Compress) add(s);
    if (c != Command::Compress) add_config_option(cmd);
    add_output_flags(cmd, out);
    for (const char* run : {"--config", "--json", "--quiet"})
        if (CLI::Option* op = cmd->get_option_no_throw(run)) op->group(to_string(Group::Run));
    for (const OptionSpec* s : user_options(c))
        if (s->tier != Tier::Essential && c != Command::Compress) add(s);
}

}  // namespace normalflow::cli
