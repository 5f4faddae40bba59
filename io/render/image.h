#pragma once
/// \file image.h
/// An 8-bit RGB raster image, the output of the headless renderer (io/render/render.h).

#include <cstddef>
#include <cstdint>
#include <vector>

namespace normalflow {

/// One pixel, 8 bits per channel, sRGB-ish display values.
struct Rgb8 {
    std::uint8_t r = 0, g = 0, b = 0;
    constexpr bool operator==(const Rgb8&) const = default;
};

/// width × height pixels, rows top to bottom, 3 bytes (R, G, B) per pixel, no padding.
struct Image {
    int width = 0;
    int height = 0;
    std::vector<std::uint8_t> rgb;  ///< 3 · width · height bytes

    Image() = default;
    /// A width × height image filled with `fill`. Sizes must be >= 0 (not checked beyond assert).
    Image(int w, int h, Rgb8 fill = {}) : width(w), height(h), rgb(std::size_t(w) * std::size_t(h) * 3) {
        for (std::size_t i = 0; i < rgb.size(); i += 3) {
            rgb[i] = fill.r;
            rgb[i + 1] = fill.g;
            rgb[i + 2] = fill.b;
        }
    }
    /// Pixel (x, y), x to the right, y down, 0-based; no bounds check.
    Rgb8 at(int x, int y) const {
        const std::size_t i = (std::size_t(y) * std::size_t(width) + std::size_t(x)) * 3;
        return {rgb[i], rgb[i + 1], rgb[i + 2]};
    }
    void set(int x, int y, Rgb8 c) {
        const std::size_t i = (std::size_t(y) * std::size_t(width) + std::size_t(x)) * 3;
        rgb[i] = c.r;
        rgb[i + 1] = c.g;
        rgb[i + 2] = c.b;
    }
};

}  // namespace normalflow
