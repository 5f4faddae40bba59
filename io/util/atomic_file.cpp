#include "io/util/atomic_file.h"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>

#include "core/errors.h"

namespace normalflow {

namespace {
std::atomic<unsigned> g_counter{0};
std::string errno_text() { return std::strerror(errno); }
}  // namespace

AtomicFile::AtomicFile(std::string path, std::string_view who) : path_(std::move(path)), who_(who) {
    if (path_.empty()) throw IoError(who_ + ": empty output path");
    std::error_code ec;
    if (std::filesystem::is_directory(path_, ec)) throw IoError(who_ + ": " + path_ + ": is a directory");
    const std::filesystem::path p(path_);
    const std::string name = p.filename().string();
    tmp_ = (p.parent_path() /
            ("." + name + ".tmp" + std::to_string(::getpid()) + "-" + std::to_string(g_counter.fetch_add(1))))
               .string();
    f_ = std::fopen(tmp_.c_str(), "wb");
    if (!f_) throw IoError(who_ + ": " + path_ + ": cannot write (" + errno_text() + ")");
}

AtomicFile::~AtomicFile() {
    if (f_) std::fclose(f_);
    if (!committed_) std::remove(tmp_.c_str());
}

void AtomicFile::write(const void* data, std::size_t bytes) {
    if (bytes == 0) return;
    if (std::fwrite(data, 1, bytes, f_) != bytes)
        throw IoError(who_ + ": " + path_ + ": write failed (" + errno_text() + ")");
}

void AtomicFile::commit() {
    if (std::fflush(f_) != 0 || std::ferror(f_))
        throw IoError(who_ + ": " + path_ + ": write failed (" + errno_text() + ")");
    const int rc = std::fclose(f_);
    f_ = nullptr;
    if (rc != 0) throw IoError(who_ + ": " + path_ + ": write failed (" + errno_text() + ")");
    if (std::rename(tmp_.c_str(), path_.c_str()) != 0)
        throw IoError(who_ + ": " + path_ + ": cannot rename temporary file into place (" + errno_text() + ")");
    committed_ = true;
}

}  // namespace normalflow
