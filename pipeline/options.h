#pragma once
/// \file options.h
/// The options table: every option a user can give the pipeline (the normalflow tool's flags, a --config file's
/// keys, the Python module's keyword arguments, the `parameters` of a --json report) declared once, with its name,
/// the field it sets, its default (the structs' own, read through the field), its range, its help, the commands
/// that take it and its tier. The command line (apps/normalflow/cli_options.cpp) and the Python module
/// (python/src/module.cpp) build their flags and keywords from it; neither names an option itself.
///
/// Names: "sigma-spatial" is the flag --sigma-spatial and the config key sigma-spatial (or sigma_spatial); with '_'
/// for '-' it is the JSON key and the Python keyword. A switch that is on by default is given off as --no-NAME
/// (NAME = false in a config file or in Python).

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "io/io.h"
#include "io/util/json.h"
#include "io/util/write_options.h"
#include "pipeline/pipeline.h"

namespace normalflow {

/// Everything a run is given: the pipeline's options, how a volume file's values are read, the Draco settings of
/// a .drc or .glb output, and whether a .vdb output also holds the normal map.
struct RunOptions {
    PipelineOptions pipeline;
    VolumeInput volume;
    DracoOptions draco;
    bool normal_map = false;
};

/// The commands that take options from the table (a bit each: OptionSpec::commands).
enum class Command : std::uint8_t {
    Smooth = 1,    ///< the whole pipeline (and batch, which runs it over files)
    Remesh = 2,    ///< re-meshing without smoothing, sharpened
    Voxelize = 4,  ///< scan conversion only
    Extract = 8,   ///< a volume file's surface
    Compress = 16  ///< a mesh written as Draco
};

/// "smooth", "remesh", "voxelize", "extract", "compress".
const char* to_string(Command c);

/// The options a command starts from: the structs' defaults, and what the command decides (remesh: no smoothing,
/// connectivity remesh, sharpen; voxelize and extract: no smoothing). Every default of the table is read here.
RunOptions default_options(Command c);

/// The pipeline's options of a run of c: options.pipeline with the command's rules applied (voxelize, extract and
/// remesh do not smooth; remesh re-meshes) and --threads given to both the scan conversion and the engine.
PipelineOptions pipeline_options(const RunOptions& options, Command c);

/// How a run reads a volume file: o.volume, resampled to o's voxel size when it gives one.
/// \throw InvalidInput when o gives a resolution or a shell (a volume keeps its grid).
VolumeInput volume_input(const RunOptions& o);

/// A mesh input: \throw InvalidInput when o sets how a volume file is read (iso, label, negate).
void refuse_volume_options(const RunOptions& o);

/// The length unit of a volume file's smoothing, unless p sets one: kVolumeLengthScaleVoxels × the file's coarsest
/// spacing (VolumeReadInfo::spacing), the scale of its staircase.
void set_volume_length_scale(PipelineOptions& p, const VolumeReadInfo& info);

/// How much an option matters to a user: --help shows the Essential tier, --help-all every tier but Library.
enum class Tier : std::uint8_t {
    Essential,  ///< what a new user sets: --help
    Advanced,   ///< model-unit knobs, special inputs and machines: --help-all
    Expert,     ///< voxel-unit knobs of the paper's modes, the refit and the fit: --help-all
    Library,    ///< comparisons with older defaults and internals: set in C++ (benchmarks), recorded in --json
};

/// What an option is about: --help's headings.
enum class Group : std::uint8_t { Input, Smoothing, OutputMesh, WebOutput, Run };

/// "Input", "Smoothing", "Output mesh", "Web output (.glb, .drc)", "Run".
const char* to_string(Group g);

/// The type of an option's field.
enum class OptionKind : std::uint8_t {
    Switch,        ///< bool
    Int,           ///< int
    Count,         ///< std::size_t
    Real,          ///< float or double (OptionSpec::single: float)
    OptionalReal,  ///< std::optional<double>: unset unless given
    Choice,        ///< an enum, one of OptionSpec::choices
    Bytes,         ///< std::size_t written as a size: 4G, 512M, 100000
};

/// One name of a Choice option and the enum's value.
struct OptionChoice {
    std::string name;
    int value;
};

/// One option of the table.
struct OptionSpec {
    std::string name;   ///< "sigma-spatial"
    std::string field;  ///< where it lands: "pipeline.smooth.sigma_spatial"
    std::string help;   ///< one line; the default is not in it (it is read from the field)
    Group group = Group::Input;
    Tier tier = Tier::Advanced;
    unsigned commands = 0;  ///< bits of Command
    OptionKind kind = OptionKind::Real;
    bool single = false;  ///< Real: the field is a float
    /// The allowed values (Int, Count, Real, Bytes): lo <= x <= hi, lo < x when lo_open.
    double lo = 0, hi = 1e300;
    bool lo_open = false;
    /// 0 is also allowed and means "decide for me": the word for it ("auto", "none"), "" when 0 is not special.
    std::string zero;
    std::vector<OptionChoice> choices;    ///< Choice
    void* (*ref)(RunOptions&) = nullptr;  ///< the field

    bool takes(Command c) const { return (commands & static_cast<unsigned>(c)) != 0; }
    /// "sigma_spatial": the JSON key and the Python keyword.
    std::string key() const;
};

/// The table, in the order --help lists it.
std::span<const OptionSpec> option_table();

/// The option named name ("sigma-spatial" or "sigma_spatial") that c takes, or nullptr.
const OptionSpec* find_option(std::string_view name, Command c);

/// The options c takes below the Library tier: the command line's flags and Python's keywords, in table order.
std::vector<const OptionSpec*> user_options(Command c);

/// Sets spec's field of o from text, as the command line and a config file give it ("0.5", "bilateral", "4G",
/// "auto", "true"). \throw InvalidInput with what is wrong, without the option's name (callers put it in front
/// in their own spelling): "'bilaterl' is not one of bilateral, guided, tv, anisotropic, isotropic, highboost, mcf".
void set_option(const OptionSpec& spec, RunOptions& o, std::string_view text);

/// spec's value in o as text that set_option takes back ("0.6", "bilateral", "auto" for an automatic 0, "" for an
/// unset OptionalReal).
std::string option_text(const OptionSpec& spec, const RunOptions& o);

/// spec's value in o as JSON (numbers, booleans, choice names, null for an unset OptionalReal).
Json option_json(const OptionSpec& spec, const RunOptions& o);

/// What values spec takes, for help and errors: "bilateral|guided|...", "> 0", "[8, 8192], or 0 (auto)".
std::string option_range(const OptionSpec& spec);

/// Checks every option of the table against its range (all tiers, whatever the command), naming the option and its
/// field: a library caller's values get the checks the command line's get (validate(PipelineOptions) runs it).
/// \throw InvalidInput "who: NAME (FIELD) = VALUE: expected RANGE".
void check_options(const RunOptions& o, const char* who);

/// The `parameters` of a --json report: every option c takes, user tiers first, as given (an automatic 0 stays 0),
/// so that the object is a config file that repeats the run; the Library tier's under "library".
Json parameters_json(const RunOptions& o, Command c);

/// The `resolved` object of a --json report: what the run decided for the automatic options (resolution, voxel
/// size, band, the length unit, iterations, normal and refit steps) and the threads it ran on.
/// scan_converted: the run scan-converted a mesh (a volume input has no resolution of its own).
Json resolved_json(const PipelineOptions& o, const PipelineReport& r, double voxel_size, bool scan_converted);

/// Sets j's "parameters" (parameters_json: the options as given) and "resolved" (resolved_json: what the run decided
/// for the automatic ones).
void set_parameters(Json& j, const RunOptions& run, Command c, const PipelineOptions& opt, const PipelineReport& r,
                    double voxel_size, bool scan_converted);

/// The report of a run of c on a mesh, one shape for the tool's --json, a batch line's "result" and Python's calls:
/// the pipeline's report (to_json), "command", "mode" (when it smoothed), "parameters" and "resolved" as above, and
/// "version". Callers add what only they know (the files, the read and write times). scan_converted: false for a
/// volume input (resolved_json).
Json run_report_json(Command c, const RunOptions& run, const PipelineReport& r, bool scan_converted = true);

}  // namespace normalflow
