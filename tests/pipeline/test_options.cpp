// The options table (pipeline/options.h): each option once, its default the structs', its range enforced,
// every value written back the way it is read (a report's parameters repeat the run).
#include <gtest/gtest.h>

#include <cstring>
#include <set>
#include <string>

#include "core/errors.h"
#include "pipeline/options.h"

namespace normalflow {
namespace {

constexpr Command kCommands[] = {Command::Smooth, Command::Remesh, Command::Voxelize, Command::Extract,
                                 Command::Compress};

TEST(Options, EachNameAndFieldOnceAndEveryFieldInsideRunOptions) {
    std::set<std::string> names, fields;
    std::set<const void*> addresses;
    RunOptions o;
    const auto* begin = reinterpret_cast<const char*>(&o);
    for (const OptionSpec& s : option_table()) {
        EXPECT_TRUE(names.insert(s.name).second) << s.name;
        EXPECT_TRUE(fields.insert(s.field).second) << s.field;
        const void* at = s.ref(o);
        EXPECT_TRUE(addresses.insert(at).second) << s.name << " writes the field of another option";
        const auto* c = static_cast<const char*>(at);
        EXPECT_TRUE(c >= begin && c < begin + sizeof o) << s.name;
        EXPECT_NE(s.commands, 0u) << s.name;
        EXPECT_FALSE(s.help.empty()) << s.name;
        EXPECT_EQ(s.name.find('_'), std::string::npos) << s.name;
        if (s.kind == OptionKind::Choice) {
            EXPECT_GE(s.choices.size(), 2u) << s.name;
        }
    }
}

TEST(Options, DefaultsAreTheStructsAndTheCommandsRules) {
    const RunOptions smooth = default_options(Command::Smooth);
    EXPECT_EQ(option_text(*find_option("mode", Command::Smooth), smooth), to_string(PipelineOptions{}.smooth.mode));
    EXPECT_EQ(option_text(*find_option("sigma_spatial", Command::Smooth), smooth),
              option_text(*find_option("sigma-spatial", Command::Smooth), RunOptions{}));
    EXPECT_EQ(option_text(*find_option("resolution", Command::Smooth), smooth), "auto");
    EXPECT_EQ(option_text(*find_option("position-bits", Command::Smooth), smooth),
              std::to_string(DracoOptions{}.position_bits));
    EXPECT_EQ(option_text(*find_option("sharpen", Command::Remesh), default_options(Command::Remesh)), "true");
    EXPECT_EQ(find_option("sharpen", Command::Smooth), nullptr);  // smoothing refuses it
    EXPECT_EQ(find_option("band", Command::Smooth), nullptr);     // raised to the engine's: resolved, not given
    EXPECT_NE(find_option("band", Command::Voxelize), nullptr);
    // the commands' rules: one place
    EXPECT_TRUE(pipeline_options(smooth, Command::Smooth).smoothing);
    EXPECT_FALSE(pipeline_options(smooth, Command::Voxelize).smoothing);
    EXPECT_EQ(pipeline_options(smooth, Command::Remesh).connectivity, Connectivity::Remesh);
    RunOptions threads = smooth;
    set_option(*find_option("threads", Command::Smooth), threads, "3");
    EXPECT_EQ(pipeline_options(threads, Command::Smooth).smooth.threads, 3);
}

TEST(Options, EveryValueIsReadBackAsWrittenAndChangesOnlyItsField) {
    for (Command c : kCommands) {
        const RunOptions defaults = default_options(c);
        for (const OptionSpec& s : option_table()) {
            if (!s.takes(c)) continue;
            RunOptions o = defaults;
            set_option(s, o, option_text(s, defaults));
            EXPECT_EQ(std::memcmp(s.ref(o), s.ref(const_cast<RunOptions&>(defaults)), 1), 0) << s.name;
            EXPECT_EQ(option_json(s, o).dump(), option_json(s, defaults).dump()) << s.name;
            // another value: only this option's text changes
            std::string other;
            switch (s.kind) {
                case OptionKind::Switch: other = option_text(s, defaults) == "true" ? "false" : "true"; break;
                case OptionKind::Choice:
                    other = s.choices.back().name == option_text(s, defaults) ? s.choices.front().name
                                                                              : s.choices.back().name;
                    break;
                case OptionKind::Bytes: other = "3G"; break;
                case OptionKind::OptionalReal: other = "2.5"; break;
                default:  // the top of the range, or a value above its bottom (2 where it has none)
                    other = std::to_string(int(s.hi < 1e9 ? s.hi : s.lo > -1e9 ? s.lo + 2 : 2));
                    break;
            }
            set_option(s, o, other);
            EXPECT_NE(option_text(s, o), option_text(s, defaults)) << s.name << " = " << other;
            for (const OptionSpec& t : option_table()) {
                if (&t != &s && t.takes(c)) {
                    EXPECT_EQ(option_text(t, o), option_text(t, defaults)) << s.name << " changed " << t.name;
                }
            }
        }
    }
}

TEST(Options, OutOfRangeAndMistypedValuesAreRefusedSayingWhatIsExpected) {
    RunOptions o = default_options(Command::Smooth);
    const auto refuses = [&](const char* name, const char* text, const char* says) {
        try {
            set_option(*find_option(name, Command::Smooth), o, text);
            ADD_FAILURE() << name << " took " << text;
        } catch (const InvalidInput& e) {
            EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
        }
    };
    refuses("mode", "bilaterl", "'bilaterl' is not one of bilateral, guided, tv, anisotropic");
    refuses("resolution", "3", "'3' is not an integer in [8, 8192], or auto");
    refuses("resolution", "64.5", "an integer");
    refuses("sigma-range", "0", "a number > 0");
    refuses("sigma-range", "nan", "a number > 0");
    refuses("iterations", "-1", "an integer in [1, 10000], or auto");
    refuses("max-memory", "4Q", "a size");
    refuses("max-memory", "1e300", "a size");         // no size_t holds it
    refuses("sigma-range", "1e300", "a number > 0");  // no float holds it
    refuses("repair", "maybe", "true or false");
    refuses("target-faces", "3", "or none");
    // the words of 0
    set_option(*find_option("resolution", Command::Smooth), o, "auto");
    EXPECT_EQ(o.pipeline.scan.resolution, 0);
    set_option(*find_option("target-faces", Command::Smooth), o, "none");
    EXPECT_EQ(o.pipeline.target_faces, 0u);
    set_option(*find_option("max-memory", Command::Smooth), o, "512M");
    EXPECT_EQ(o.pipeline.max_memory_bytes, std::size_t(512) << 20);
    set_option(*find_option("iso", Command::Smooth), o, "-300");
    EXPECT_EQ(o.volume.iso, -300.0);
}

TEST(Options, CheckOptionsNamesALibraryCallersBadValue) {
    RunOptions o = default_options(Command::Smooth);
    EXPECT_NO_THROW(check_options(o, "run"));
    o.pipeline.smooth.active_band = 10;  // Library tier: no flag, still checked
    try {
        check_options(o, "run");
        ADD_FAILURE() << "active_band 10 passed";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find(
                      "run: active_band (pipeline.smooth.active_band) = 10: expected a number in [1.5, 5]"),
                  std::string::npos)
            << e.what();
    }
}

TEST(Options, ParametersRepeatTheRun) {
    RunOptions o = default_options(Command::Smooth);
    set_option(*find_option("mode", Command::Smooth), o, "tv");
    set_option(*find_option("sigma-range", Command::Smooth), o, "0.3");
    set_option(*find_option("repair", Command::Smooth), o, "false");
    set_option(*find_option("iso", Command::Smooth), o, "0.5");
    o.pipeline.smooth.extend_by_gather = true;  // a Library field, recorded apart
    Json given = parameters_json(o, Command::Smooth);
    // every key back through set_option (as a config file's or Python's value) gives the same options
    RunOptions back = default_options(Command::Smooth);
    for (const OptionSpec& s : option_table()) {
        if (!s.takes(Command::Smooth)) continue;
        const Json& j = s.tier == Tier::Library ? given["library"][s.key()] : given[s.key()];
        std::string text = j.dump();
        if (text.size() >= 2 && text.front() == '"') text = text.substr(1, text.size() - 2);
        if (text == "null") text.clear();
        set_option(s, back, text);
    }
    EXPECT_EQ(parameters_json(back, Command::Smooth).dump(), given.dump());
    EXPECT_EQ(given["sigma_range"].dump(), "0.3");  // a float as written, not 0.30000001192092896
    EXPECT_EQ(given["library"]["extend_by_gather"].dump(), "true");
    EXPECT_EQ(find_option("decimator", Command::Smooth)->tier, Tier::Library);  // recorded, not a flag
}

TEST(Options, EveryUserOptionHasAGroupAndTheEssentialTierIsShort) {
    for (Command c : {Command::Smooth, Command::Remesh, Command::Voxelize, Command::Extract}) {
        std::size_t essential = 0;
        for (const OptionSpec* s : user_options(c)) essential += s->tier == Tier::Essential;
        EXPECT_LE(essential, 11u) << to_string(c) << ": --help adds -h, --config, --json and --quiet";
    }
}

}  // namespace
}  // namespace normalflow
