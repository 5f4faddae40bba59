#pragma once
/// \file color_map.h
/// Colour maps for per-vertex scalars and a legend bar image to go with them.

#include <optional>
#include <string>

#include "io/render/image.h"

namespace normalflow {

/// Which colour map turns a scalar in [0, 1] into a colour.
enum class ColorMap {
    Viridis,    ///< perceptually uniform sequential map (van der Walt & Smith, matplotlib 2.0), dark purple to yellow
    Diverging,  ///< blue–white–red (ColorBrewer RdBu reversed): for signed values, 0.5 is white
    Gray,       ///< black to white
};

/// The colour of t under `map`: piecewise-linear between the map's stops (9 for Viridis, 7 for Diverging).
/// t is clamped to [0, 1]; NaN maps to t = 0. map_color(ColorMap::Viridis, 0) = (68, 1, 84).
Rgb8 map_color(ColorMap map, double t);

/// How render_legend lays the bar out.
struct LegendOptions {
    int width = 400;                 ///< image width, pixels, in [64, 16384]
    int height = 48;                 ///< image height, pixels, in [32, 16384]; the bar takes what the labels leave
    Rgb8 background{255, 255, 255};  ///< image background
    Rgb8 ink{0, 0, 0};               ///< border, ticks and labels
    int ticks = 5;  ///< evenly spaced ticks including both ends, in [2, 11]; ends and middle are labelled
    /// When set, a swatch of this colour right of the bar, for values above hi (RenderOptions::over_color).
    std::optional<Rgb8> over_color{};
};

/// A horizontal colour bar from lo (left) to hi (right) with ticks and numeric labels ("%.3g", drawn with a
/// built-in 5×7 pixel font scaled ×2), and with opt.over_color a swatch of that colour after it, labelled "+".
/// Deterministic.
/// \throw InvalidInput if the options are out of range or lo, hi are not finite.
/// Cost: O(width · height).
Image render_legend(ColorMap map, double lo, double hi, const LegendOptions& opt = {});

/// Draws text (digits, '.', '-', '+', 'e', 'E', space; other characters are blank) with the 5×7 font scaled by
/// `scale` >= 1, its top-left corner at (x, y); pixels outside the image are clipped.
void draw_text(Image& img, int x, int y, const std::string& text, Rgb8 ink, int scale = 2);

/// Width in pixels of draw_text's output for text at scale.
int text_width(const std::string& text, int scale = 2);

}  // namespace normalflow
