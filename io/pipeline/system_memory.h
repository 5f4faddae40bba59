#pragma once
/// \file system_memory.h
/// What the system has: available and peak memory, for the pipeline's memory check and reports.

#include <cstddef>
#include <string>

namespace normalflow {

/// Memory the system can give this process now (MemAvailable of /proc/meminfo), bytes; 0 if unknown.
std::size_t available_memory_bytes();

/// Peak resident memory of this process, bytes (getrusage; 0 where unknown).
std::size_t peak_memory_bytes();

/// "1.23 GB"-style rendering of a byte count.
std::string format_bytes(double bytes);

}  // namespace normalflow
