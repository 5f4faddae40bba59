#pragma once
/// \file png.h
/// PNG encoding of an RGB8 image (W3C PNG 2nd edition: signature, IHDR, one IDAT, IEND; colour type 2,
/// bit depth 8, no interlace, filter type 0 on every row).

#include <cstdint>
#include <string>
#include <vector>

#include "io/render/image.h"

namespace normalflow {

/// How encode_png compresses the IDAT stream.
enum class PngCompression {
    Deflate,  ///< zlib compress2, level 6 (falls back to Stored in a build without zlib)
    Stored,   ///< uncompressed deflate blocks: larger files, no zlib needed
};

/// The bytes of a PNG file holding img. Same image, same bytes (for a given zlib version).
/// CRC-32 (ISO 3309) and Adler-32 are computed here; zlib only deflates.
/// \throw InvalidInput if img is empty, larger than 32768 pixels on a side, or rgb.size() != 3 · width · height.
/// Cost: O(width · height); about 5 ms for 400 × 400 with Deflate.
std::vector<std::uint8_t> encode_png(const Image& img, PngCompression compression = PngCompression::Deflate);

/// Writes img as a PNG file at path, atomically (AtomicFile: a failure leaves no partial file).
/// \throw InvalidInput as encode_png; IoError naming the path if it cannot be written.
void write_png(const std::string& path, const Image& img, PngCompression compression = PngCompression::Deflate);

/// CRC-32 of bytes as PNG and zlib define it (polynomial 0xEDB88320, initial and final XOR 0xFFFFFFFF).
std::uint32_t crc32_png(const std::uint8_t* data, std::size_t size, std::uint32_t crc = 0);

}  // namespace normalflow
