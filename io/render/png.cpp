#include "io/render/png.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <string>

#include "core/errors.h"
#include "io/util/atomic_file.h"
#ifdef NORMALFLOW_HAS_ZLIB
#include <zlib.h>
#endif

namespace normalflow {

namespace {

constexpr std::array<std::uint32_t, 256> make_crc_table() {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t n = 0; n < 256; ++n) {
        std::uint32_t c = n;
        for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
        t[n] = c;
    }
    return t;
}
constexpr std::array<std::uint32_t, 256> kCrcTable = make_crc_table();

void put32(std::vector<std::uint8_t>& out, std::uint32_t v) {
    out.push_back(std::uint8_t(v >> 24));
    out.push_back(std::uint8_t(v >> 16));
    out.push_back(std::uint8_t(v >> 8));
    out.push_back(std::uint8_t(v));
}

void chunk(std::vector<std::uint8_t>& out, const char type[4], const std::uint8_t* data, std::size_t size) {
    put32(out, std::uint32_t(size));
    const std::size_t start = out.size();
    out.insert(out.end(), type, type + 4);
    if (size) out.insert(out.end(), data, data + size);
    put32(out, crc32_png(out.data() + start, out.size() - start));
}

std::uint32_t adler32(const std::vector<std::uint8_t>& d) {
    std::uint32_t a = 1, b = 0;
    for (std::uint8_t x : d) {
        a = (a + x) % 65521u;
        b = (b + a) % 65521u;
    }
    return (b << 16) | a;
}

// A zlib stream of stored (uncompressed) deflate blocks of at most 65535 bytes (RFC 1950, RFC 1951 §3.2.4).
std::vector<std::uint8_t> zlib_stored(const std::vector<std::uint8_t>& raw) {
    std::vector<std::uint8_t> z{0x78, 0x01};
    std::size_t pos = 0;
    do {
        const std::size_t n = std::min<std::size_t>(65535, raw.size() - pos);
        const bool last = pos + n == raw.size();
        z.push_back(last ? 1 : 0);
        z.push_back(std::uint8_t(n & 0xff));
        z.push_back(std::uint8_t(n >> 8));
        z.push_back(std::uint8_t(~n & 0xff));
        z.push_back(std::uint8_t((~n >> 8) & 0xff));
        z.insert(z.end(), raw.begin() + std::ptrdiff_t(pos), raw.begin() + std::ptrdiff_t(pos + n));
        pos += n;
    } while (pos < raw.size());
    put32(z, adler32(raw));
    return z;
}

}  // namespace

std::uint32_t crc32_png(const std::uint8_t* data, std::size_t size, std::uint32_t crc) {
    std::uint32_t c = crc ^ 0xFFFFFFFFu;
    for (std::size_t i = 0; i < size; ++i) c = kCrcTable[(c ^ data[i]) & 0xffu] ^ (c >> 8);
    return c ^ 0xFFFFFFFFu;
}

std::vector<std::uint8_t> encode_png(const Image& img, PngCompression compression) {
    if (img.width < 1 || img.height < 1 || img.width > 32768 || img.height > 32768)
        throw InvalidInput("encode_png: image size " + std::to_string(img.width) + " x " + std::to_string(img.height) +
                           " out of range, expected 1..32768 on each side");
    const std::size_t row = std::size_t(img.width) * 3;
    if (img.rgb.size() != row * std::size_t(img.height))
        throw InvalidInput("encode_png: " + std::to_string(img.rgb.size()) + " pixel bytes, expected " +
                           std::to_string(row * std::size_t(img.height)));
    // Filter type 0 (None) on every row: a leading 0 byte, then the row.
    std::vector<std::uint8_t> raw;
    raw.reserve((row + 1) * std::size_t(img.height));
    for (int y = 0; y < img.height; ++y) {
        raw.push_back(0);
        raw.insert(raw.end(), img.rgb.begin() + std::ptrdiff_t(row * std::size_t(y)),
                   img.rgb.begin() + std::ptrdiff_t(row * std::size_t(y + 1)));
    }
    std::vector<std::uint8_t> z;
#ifdef NORMALFLOW_HAS_ZLIB
    if (compression == PngCompression::Deflate) {
        uLongf size = compressBound(uLong(raw.size()));
        z.resize(size);
        if (compress2(z.data(), &size, raw.data(), uLong(raw.size()), 6) != Z_OK)
            throw OutOfMemory("encode_png: zlib compress2 failed");
        z.resize(size);
    }
#endif
    if (z.empty()) z = zlib_stored(raw);

    std::vector<std::uint8_t> out{0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    std::vector<std::uint8_t> ihdr;
    put32(ihdr, std::uint32_t(img.width));
    put32(ihdr, std::uint32_t(img.height));
    ihdr.insert(ihdr.end(), {8, 2, 0, 0, 0});  // bit depth 8, colour type 2 (RGB), deflate, filter 0, no interlace
    chunk(out, "IHDR", ihdr.data(), ihdr.size());
    chunk(out, "IDAT", z.data(), z.size());
    chunk(out, "IEND", nullptr, 0);
    return out;
}

void write_png(const std::string& path, const Image& img, PngCompression compression) {
    const std::vector<std::uint8_t> bytes = encode_png(img, compression);
    AtomicFile f(path, "write_png");
    f.write(bytes.data(), bytes.size());
    f.commit();
}

}  // namespace normalflow
