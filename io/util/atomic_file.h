#pragma once
/// \file atomic_file.h
/// Writing a file so that a failure never leaves a partial file and never damages an existing one:
/// the data goes to a temporary file in the same folder, which is renamed over the target only
/// by commit(). If the object is destroyed without commit() (an exception, a cancel), the temporary
/// file is removed and the target is untouched.

#include <cstdio>
#include <string>
#include <string_view>

namespace normalflow {

class AtomicFile {
public:
    /// Opens a temporary file beside `path` for binary writing.
    /// \throw IoError naming `who` and `path` if the folder is not writable.
    AtomicFile(std::string path, std::string_view who);
    ~AtomicFile();
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    /// The open stream (binary mode).
    std::FILE* stream() { return f_; }
    /// Writes bytes; throws IoError on failure (disk full, ...).
    void write(const void* data, std::size_t bytes);
    void write(std::string_view s) { write(s.data(), s.size()); }
    /// Flushes, closes and renames the temporary file over the target. Throws IoError on failure.
    void commit();

    const std::string& path() const { return path_; }
    /// The temporary file, for libraries that can only write by file name (e.g. OpenVDB's io::File):
    /// let them (over)write temp_path() without using stream(), then call commit().
    const std::string& temp_path() const { return tmp_; }

private:
    std::string path_, tmp_, who_;
    std::FILE* f_ = nullptr;
    bool committed_ = false;
};

}  // namespace normalflow
