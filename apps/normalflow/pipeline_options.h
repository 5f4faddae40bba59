#pragma once
// The flags that parse into PipelineOptions (voxelize, extract, smooth) and into VolumeInput, registered on
// a CLI11 command. The normalflow tool and the Python module (python/, whose keyword arguments are these
// flags) share them, so both have the same options, defaults (the library's) and checks.
#include <CLI/CLI.hpp>

#include "io/io.h"
#include "io/pipeline/pipeline.h"

namespace normalflow::cli {

/// --resolution, --voxel-size, --shell, --no-repair, --distance, --max-memory, --threads (voxelize, smooth).
void add_grid_options(CLI::App* cmd, PipelineOptions& p);

/// --iso, --label, --negate (and --voxel-size when voxel_size): how a dense volume file's values are read.
void add_volume_input_options(CLI::App* cmd, VolumeInput& v, bool voxel_size);

/// The engine's flags (--mode, --iterations, ..., --second-order) and what comes back (--connectivity,
/// --closed, the fit's); smooth.
void add_smooth_options(CLI::App* cmd, PipelineOptions& p);

/// remesh: --no-sharpen (p.sharpen is set true first: the default) and --closed.
void add_remesh_options(CLI::App* cmd, PipelineOptions& p);

/// --target-faces, --max-error and --decimator: the decimation of a re-meshed result (volume_to_mesh).
void add_decimation_options(CLI::App* cmd, PipelineOptions& p);

/// The length unit of a volume file's smoothing, unless the flags set one: kVolumeLengthScaleVoxels × the file's
/// coarsest spacing (VolumeReadInfo::spacing), the scale of its staircase.
void set_volume_length_scale(PipelineOptions& p, const VolumeReadInfo& info);

}  // namespace normalflow::cli
