#pragma once
// The subcommands of the normalflow tool. main.cpp parses flags into these structs (the library's own
// option structs where one exists) and calls run_*; each run_* lives in its own cmd_*.cpp.
#include <string>

#include "cli_support.h"

namespace normalflow::cli {

struct InfoArgs {
    std::string input;
    bool self_intersections = false;  ///< also count intersecting triangle pairs (CGAL; slower)
    OutputFlags out;
};
int run_info(const InfoArgs& a);

}  // namespace normalflow::cli
