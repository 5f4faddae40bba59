#include "io/render/color_map.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <span>
#include <string>

#include "core/errors.h"

namespace normalflow {

namespace {

// matplotlib's viridis sampled at 9 evenly spaced points (R's viridisLite::viridis(9)).
constexpr Rgb8 kViridis[] = {{68, 1, 84},    {71, 45, 123}, {59, 82, 139},  {44, 114, 142}, {33, 144, 140},
                             {39, 173, 129}, {92, 200, 99}, {170, 220, 50}, {253, 231, 37}};
// ColorBrewer RdBu, 7 classes, reversed: blue (low) – white – red (high).
constexpr Rgb8 kDiverging[] = {{33, 102, 172},  {103, 169, 207}, {209, 229, 240}, {247, 247, 247},
                               {253, 219, 199}, {239, 138, 98},  {178, 24, 43}};
constexpr Rgb8 kGray[] = {{0, 0, 0}, {255, 255, 255}};

Rgb8 interpolate(std::span<const Rgb8> stops, double t) {
    if (!(t > 0)) return stops.front();  // also NaN
    if (t >= 1) return stops.back();
    const double s = t * double(stops.size() - 1);
    const std::size_t i = std::min(stops.size() - 2, std::size_t(s));
    const double u = s - double(i);
    auto mix = [u](std::uint8_t a, std::uint8_t b) {
        return static_cast<std::uint8_t>(std::lround(double(a) + u * (double(b) - double(a))));
    };
    const Rgb8 a = stops[i], b = stops[i + 1];
    return {mix(a.r, b.r), mix(a.g, b.g), mix(a.b, b.b)};
}

// A 5×7 pixel font: 7 rows of 5 bits (bit 4 = leftmost column).
struct Glyph {
    char c;
    std::uint8_t rows[7];
};
constexpr Glyph kFont[] = {
    {'0', {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}}, {'1', {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'2', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}}, {'3', {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E}},
    {'4', {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}}, {'5', {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E}},
    {'6', {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}}, {'7', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
    {'8', {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}}, {'9', {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C}},
    {'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C}}, {'-', {0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00}},
    {'+', {0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00}}, {'e', {0x00, 0x00, 0x0E, 0x11, 0x1F, 0x10, 0x0E}},
    {'E', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F}},
};

const Glyph* glyph(char c) {
    for (const Glyph& g : kFont)
        if (g.c == c) return &g;
    return nullptr;
}

void fill_rect(Image& img, int x0, int y0, int x1, int y1, Rgb8 c) {  // [x0, x1) × [y0, y1), clipped
    for (int y = std::max(0, y0); y < std::min(img.height, y1); ++y)
        for (int x = std::max(0, x0); x < std::min(img.width, x1); ++x) img.set(x, y, c);
}

std::string label(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3g", v);
    return buf;
}

}  // namespace

Rgb8 map_color(ColorMap map, double t) {
    switch (map) {
        case ColorMap::Viridis: return interpolate(kViridis, t);
        case ColorMap::Diverging: return interpolate(kDiverging, t);
        case ColorMap::Gray: return interpolate(kGray, t);
    }
    return interpolate(kGray, t);
}

int text_width(const std::string& text, int scale) { return text.empty() ? 0 : int(text.size()) * 6 * scale - scale; }

void draw_text(Image& img, int x, int y, const std::string& text, Rgb8 ink, int scale) {
    scale = std::max(1, scale);
    for (std::size_t k = 0; k < text.size(); ++k) {
        const Glyph* g = glyph(text[k]);
        if (!g) continue;
        const int gx = x + int(k) * 6 * scale;
        for (int r = 0; r < 7; ++r)
            for (int c = 0; c < 5; ++c)
                if (g->rows[r] & (0x10 >> c))
                    fill_rect(img, gx + c * scale, y + r * scale, gx + (c + 1) * scale, y + (r + 1) * scale, ink);
    }
}

Image render_legend(ColorMap map, double lo, double hi, const LegendOptions& opt) {
    if (opt.width < 64 || opt.width > 16384 || opt.height < 32 || opt.height > 16384)
        throw InvalidInput("render_legend: size " + std::to_string(opt.width) + " x " + std::to_string(opt.height) +
                           " out of range, expected width 64..16384 and height 32..16384");
    if (opt.ticks < 2 || opt.ticks > 11)
        throw InvalidInput("render_legend: " + std::to_string(opt.ticks) + " ticks, expected 2..11");
    if (!std::isfinite(lo) || !std::isfinite(hi)) throw InvalidInput("render_legend: range is not finite");
    Image img(opt.width, opt.height, opt.background);
    const int scale = 2, text_h = 7 * scale;
    const int margin = 4, tick_len = 4;
    const int swatch = opt.over_color ? std::max(12, opt.width / 16) : 0;  // the over-range swatch's width
    const int bx0 = margin, bx1 = opt.width - margin - (swatch > 0 ? swatch + margin : 0);  // bar columns [bx0, bx1)
    const int by0 = margin, by1 = opt.height - margin - text_h - tick_len - 2;
    // Border, then the colours inside it.
    fill_rect(img, bx0, by0, bx1, by1, opt.ink);
    const int ix0 = bx0 + 1, ix1 = bx1 - 1;
    for (int x = ix0; x < ix1; ++x) {
        const double t = ix1 - ix0 > 1 ? double(x - ix0) / double(ix1 - ix0 - 1) : 0.0;
        fill_rect(img, x, by0 + 1, x + 1, by1 - 1, map_color(map, t));
    }
    const int label_y = by1 + tick_len + 2;
    for (int k = 0; k < opt.ticks; ++k) {
        const double t = double(k) / double(opt.ticks - 1);
        const int x = ix0 + int(std::lround(t * double(ix1 - ix0 - 1)));
        fill_rect(img, x, by1, x + 1, by1 + tick_len, opt.ink);
        const bool labelled = k == 0 || k == opt.ticks - 1 || 2 * k == opt.ticks - 1;
        if (!labelled) continue;
        const std::string s = label(lo + t * (hi - lo));
        const int w = text_width(s, scale);
        const int lx = k == 0 ? bx0 : (k == opt.ticks - 1 ? bx1 - w : x - w / 2);
        draw_text(img, lx, label_y, s, opt.ink, scale);
    }
    if (opt.over_color) {
        const int sx0 = opt.width - margin - swatch, sx1 = opt.width - margin;
        fill_rect(img, sx0, by0, sx1, by1, opt.ink);
        fill_rect(img, sx0 + 1, by0 + 1, sx1 - 1, by1 - 1, *opt.over_color);
        draw_text(img, sx0 + (swatch - text_width("+", scale)) / 2, label_y, "+", opt.ink, scale);
    }
    return img;
}

}  // namespace normalflow
