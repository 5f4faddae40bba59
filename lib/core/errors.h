#pragma once
/// \file errors.h
/// The exception family of normalflow. Library code never prints or exits; it throws one of these
/// with a message that says who, where, what was expected and what was found, e.g.
/// `read_ply: scan.ply, line 12: face has 5 indices, expected 3`. apps/ map them to exit codes.

#include <stdexcept>
#include <string>

namespace normalflow {

/// Input that cannot be processed: malformed file contents, bad parameters, empty meshes.
struct InvalidInput : std::invalid_argument {
    using std::invalid_argument::invalid_argument;
};

/// A file could not be opened, read, written or renamed.
struct IoError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

/// A computation produced NaN/Inf or left its stability bounds.
struct NumericalError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

/// The run was cancelled through Progress::should_stop (or SIGINT in the apps).
struct Cancelled : std::runtime_error {
    using std::runtime_error::runtime_error;
};

/// The run would need more memory than allowed.
struct OutOfMemory : std::runtime_error {
    using std::runtime_error::runtime_error;
};

}  // namespace normalflow
