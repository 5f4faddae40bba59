#pragma once
/// \file run_file.h
/// One file through a command: read → run → write, with one report. The normalflow tool's voxelize, extract,
/// smooth and remesh, and each file of its batch, are this call.

#include <string>
#include <vector>

#include "core/progress.h"
#include "io/util/json.h"
#include "pipeline/options.h"

namespace normalflow {

/// What run_file did.
struct FileRun {
    /// The report: run_report_json's keys (a mesh input), or the volume input's (command, mode, input, smooth,
    /// parameters, resolved, extract, decimate); with "input" (the file as read), "output" (the file as written),
    /// "seconds" (read, the stages, write) and "warnings" (the reader's first).
    Json report;
    std::vector<std::string> notes;  ///< lines for the user beyond the warnings (why the engine stopped early)
    std::string summary;             ///< "OUT (N triangles, decimated from M; ...)": what was written
    std::size_t triangles = 0;       ///< triangles written; 0 for a volume
};

/// Reads input, runs command c (not Compress) with run's options and writes output: a mesh (.ply, .obj, .off,
/// .stl, .glb with Draco, .drc) or, for voxelize and smooth, a volume (.vdb, .nrrd; smooth takes a volume file in
/// too). The output is written whole or not at all, and a bad output path is refused before any work.
/// \throw InvalidInput naming the file (bad options, a bad input, an unknown output format); IoError, OutOfMemory,
/// NumericalError, Cancelled as the stages throw them. memory_limit > 0: the memory check's limit where run gives
/// none (batch: each job's share of the memory available); the report's parameters keep what run gave.
FileRun run_file(Command c, const std::string& input, const std::string& output, const RunOptions& run,
                 Progress* progress = nullptr, std::size_t memory_limit = 0);

}  // namespace normalflow
