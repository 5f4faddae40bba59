#pragma once
// The subcommands of the normalflow tool. Each add_*_command registers one subcommand on the app:
// its flags (parsed into the library's option structs where one exists) and its run function.
// Each lives in its own cmd_*.cpp; adding a command is one line here, one in main.cpp and one in
// CMakeLists.txt.
#include "cli_support.h"
#include "io/util/write_options.h"

namespace normalflow::cli {

void add_info_command(CLI::App& app);       // cmd_info.cpp
void add_voxelize_command(CLI::App& app);   // cmd_pipeline.cpp
void add_extract_command(CLI::App& app);    // cmd_pipeline.cpp
void add_smooth_command(CLI::App& app);     // cmd_pipeline.cpp
void add_remesh_command(CLI::App& app);     // cmd_pipeline.cpp
void add_batch_command(CLI::App& app);      // cmd_batch.cpp
void add_convert_command(CLI::App& app);    // cmd_convert.cpp
void add_taubin_command(CLI::App& app);     // cmd_taubin.cpp
void add_laplacian_command(CLI::App& app);  // cmd_taubin.cpp
void add_bilateral_command(CLI::App& app);  // cmd_taubin.cpp
void add_noise_command(CLI::App& app);      // cmd_noise.cpp
void add_compare_command(CLI::App& app);    // cmd_compare.cpp
void add_compress_command(CLI::App& app);   // cmd_compress.cpp
void add_cleanup_command(CLI::App& app);    // cmd_cleanup.cpp
void add_tetmesh_command(CLI::App& app);    // cmd_tetmesh.cpp

}  // namespace normalflow::cli
