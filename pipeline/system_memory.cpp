#include "pipeline/system_memory.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#if defined(__unix__) || defined(__APPLE__)
#include <sys/resource.h>
#endif

#include "core/errors.h"

namespace normalflow {

std::size_t available_memory_bytes() {
    std::FILE* f = std::fopen("/proc/meminfo", "r");
    if (!f) return 0;
    char line[256];
    std::size_t kb = 0;
    while (std::fgets(line, sizeof line, f))
        if (std::sscanf(line, "MemAvailable: %zu kB", &kb) == 1) break;
    std::fclose(f);
    return kb * 1024;
}

std::size_t peak_memory_bytes() {
#if defined(__unix__) || defined(__APPLE__)
    rusage ru{};
    getrusage(RUSAGE_SELF, &ru);
    return std::size_t(ru.ru_maxrss) * 1024;  // Linux: kilobytes
#else
    return 0;
#endif
}

std::string format_bytes(double bytes) {
    char buf[64];
    if (bytes >= 1e9)
        std::snprintf(buf, sizeof buf, "%.2f GB", bytes / 1e9);
    else if (bytes >= 1e6)
        std::snprintf(buf, sizeof buf, "%.1f MB", bytes / 1e6);
    else
        std::snprintf(buf, sizeof buf, "%.0f kB", bytes / 1e3);
    return buf;
}

std::size_t parse_bytes(const std::string& text) {
    char* end = nullptr;
    const double value = std::strtod(text.c_str(), &end);
    std::string rest(end ? end : "");
    if (!rest.empty() && (rest.back() == 'B' || rest.back() == 'b')) rest.pop_back();
    double unit = 0;  // 0: not a known suffix
    if (rest.empty())
        unit = 1;
    else if (rest == "K" || rest == "k")
        unit = 1024.0;
    else if (rest == "M" || rest == "m")
        unit = 1024.0 * 1024;
    else if (rest == "G" || rest == "g")
        unit = 1024.0 * 1024 * 1024;
    else if (rest == "T" || rest == "t")
        unit = 1024.0 * 1024 * 1024 * 1024;
    if (end == text.c_str() || unit == 0 || !(value > 0) || !(value * unit < 0x1p62))  // 4 EiB, a size_t
        throw InvalidInput("'" + text + "' is not a size (examples: 4G, 512M, 100000)");
    return static_cast<std::size_t>(value * unit);
}

}  // namespace normalflow
