#pragma once
/// \file nrrd_reader.h
/// Internals of the NRRD reader (io/formats/nrrd.h), shared by its two files: the header's parser
/// (nrrd_header.cpp: the fields, the sizes, type, encoding and skips, the geometry) and the data's
/// reader (nrrd.cpp: the raw, gzip and ascii samples, and their conversion into a Volume or a
/// ScalarImage). Not part of the public API.

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/errors.h"
#include "core/vec.h"
#include "io/formats/nrrd.h"

namespace normalflow::detail {

enum class Scalar { I8, U8, I16, U16, I32, U32, F32, F64 };

inline std::size_t scalar_bytes(Scalar s) {
    switch (s) {
        case Scalar::I8:
        case Scalar::U8: return 1;
        case Scalar::I16:
        case Scalar::U16: return 2;
        case Scalar::I32:
        case Scalar::U32:
        case Scalar::F32: return 4;
        case Scalar::F64: return 8;
    }
    return 0;
}

/// Closes a FILE* on scope exit.
struct FileCloser {
    void operator()(std::FILE* f) const {
        if (f) std::fclose(f);
    }
};
using FilePtr = std::unique_ptr<std::FILE, FileCloser>;

/// Where the samples of a NRRD file lie, as its header says: sample (i, j, k) at origin + i·axes[0] +
/// j·axes[1] + k·axes[2].
struct NrrdGeometry {
    enum class From { Default, Spacings, Directions } from = From::Default;
    std::array<Vec3d, 3> axes{Vec3d{1, 0, 0}, Vec3d{0, 1, 0}, Vec3d{0, 0, 1}};
    Vec3d origin;
    std::string text;  ///< the spacings or space directions field as written, for messages
};

/// Parser state for one NRRD file (and its detached data file); every error names the header file
/// and starts with `who` (read_nrrd, read_nrrd_image).
///
/// Use: parse_header(), geometry(), open_data(), then read_samples() until every sample is read.
class NrrdReader {
public:
    NrrdReader(const std::string& path, const char* who);
    ~NrrdReader();

    /// Streams the samples into a narrow-band Volume (read_nrrd).
    Volume read_volume(const VolumeReadOptions& opt);
    /// Reads every sample into a dense image (read_nrrd_image).
    ScalarImage read_image();

private:
    [[noreturn]] void bad(const std::string& what) const { throw InvalidInput(who_ + ": " + path_ + ": " + what); }
    [[noreturn]] void bad_line(const std::string& what) const { bad("line " + std::to_string(line_no_) + ": " + what); }
    [[noreturn]] void io_error(const std::string& what) const { throw IoError(who_ + ": " + path_ + ": " + what); }

    /// Opens the header file and parses the header; the stream is left at the first byte after it.
    void parse_header();
    bool read_line(std::string& line);
    std::vector<double> parse_numbers(const std::string& s, std::size_t expected, const char* field);
    std::vector<std::optional<std::array<double, 3>>> parse_vectors(const std::string& s);
    /// The geometry fields, parsed (finite numbers, three spatial axes), not yet judged.
    NrrdGeometry geometry();
    /// Opens the detached data file if there is one, applies line skip and byte skip, and checks that
    /// the data can hold what the sizes claim (before anything is allocated).
    void open_data();
    std::uint64_t sample_count() const {
        return std::uint64_t(sizes_[0]) * std::uint64_t(sizes_[1]) * std::uint64_t(sizes_[2]);
    }

    // Data sources: fill exactly `bytes` bytes or throw.
    void read_raw(void* dst, std::size_t bytes);
    void read_gzip(void* dst, std::size_t bytes);
    void read_ascii(double* dst, std::size_t count);
    void read_samples(double* dst, std::size_t count);

    std::string path_;
    std::string who_;
    FilePtr f_;
    std::uint64_t file_size_ = 0;  // of the file f_ reads: the header file, then the data file
    std::size_t header_bytes_ = 0;
    int line_no_ = 0;

    std::map<std::string, std::string> fields_;  // lower-case field name -> description
    std::map<std::string, std::string> keys_;    // key:=value pairs
    std::string data_file_;                      // detached data file as written, or empty
    Scalar type_ = Scalar::F32;
    std::array<std::int64_t, 3> sizes_{0, 0, 0};
    enum class Encoding { Raw, Gzip, Ascii } encoding_ = Encoding::Raw;
    bool swap_ = false;
    std::int64_t byte_skip_ = 0;
    std::int64_t line_skip_ = 0;
    std::uint64_t samples_read_ = 0;

    struct Inflater;  // the gzip stream's state (nrrd.cpp)
    std::unique_ptr<Inflater> z_;
    std::vector<char> raw_buf_;
};

}  // namespace normalflow::detail
