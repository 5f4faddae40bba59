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

/// "4G", "512M", "1.5g", "100000": a byte count (K, M, G, T are powers of 1024; a trailing B is allowed).
/// \throw InvalidInput "'TEXT' is not a size (examples: 4G, 512M, 100000)".
std::size_t parse_bytes(const std::string& text);

}  // namespace normalflow
