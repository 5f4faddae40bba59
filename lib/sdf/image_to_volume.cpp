#include "sdf/image_to_volume.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include "band/band.h"
#include "band/iterate.h"
#include "band/layout.h"
#include "band/run_control.h"
#include "core/errors.h"

namespace normalflow {

namespace {

constexpr double kMaxSamples = double(1ull << 36);  // a grid beyond 68 G samples is a mistake

std::string num(double x) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", x);
    return buf;
}

/// F at image sample value f: negative inside.
struct Field {
    ImageSurface s;
    float operator()(float f) const {
        if (s.label) return double(f) == *s.label ? -0.5f : 0.5f;
        return float(s.negate ? s.iso - double(f) : double(f) - s.iso);
    }
};

}  // namespace

Placement placement_from_axes(const std::array<Vec3d, 3>& axes, const Vec3d& origin) {
    Placement p;
    p.rotation[0] = normalized(axes[0]);
    p.rotation[1] = normalized(axes[1] - p.rotation[0] * dot(p.rotation[0], axes[1]));
    p.rotation[2] = cross(p.rotation[0], p.rotation[1]);
    if (dot(p.rotation[2], axes[2]) < 0) p.rotation[2] = -p.rotation[2];
    p.translation = origin;
    return p;
}

void check_image(const ScalarImage& image, const char* who) {
    const auto bad = [&](const std::string& what) { throw InvalidInput(std::string(who) + ": image " + what); };
    for (int a = 0; a < 3; ++a)
        if (image.dims[a] < 1)
            bad("dims must be >= 1, got " + std::to_string(image.dims[0]) + " x " + std::to_string(image.dims[1]) +
                " x " + std::to_string(image.dims[2]));
    if (image.values.size() != image.sample_count())
        bad("has " + std::to_string(image.values.size()) + " values for " + std::to_string(image.sample_count()) +
            " samples");
    if (!is_finite(image.origin)) bad("origin is not finite");
    for (int a = 0; a < 3; ++a) {
        if (!is_finite(image.axes[a]) || !(norm(image.axes[a]) > 0))
            bad("axis " + std::to_string(a) + " is zero or not finite");
        for (int b = 0; b < a; ++b) {
            const double c = dot(image.axes[a], image.axes[b]) / (norm(image.axes[a]) * norm(image.axes[b]));
            if (std::abs(c) > 1e-4)
                bad("axes " + std::to_string(b) + " and " + std::to_string(a) + " are not orthogonal (cosine " +
                    num(c) + "); sheared grids are not supported");
        }
    }
    for (std::size_t i = 0; i < image.values.size(); ++i)
        if (!std::isfinite(image.values[i])) bad("sample " + std::to_string(i) + " is NaN or infinite");
}

std::optional<double> binary_mask_label(const ScalarImage& image) {
    if (image.values.empty()) return std::nullopt;
    float a = image.values[0], b = a;
    bool two = false;
    for (const float v : image.values) {
        if (v == a || (two && v == b)) continue;
        if (two) return std::nullopt;
        b = v;
        two = true;
    }
    if (!two) return std::nullopt;
    if (a == 0.0f) return double(b);
    if (b == 0.0f) return double(a);
    return std::nullopt;
}

Volume image_to_volume(const ScalarImage& image, const ImageToVolumeOptions& options, Progress* progress) {
    const char* who = "image_to_volume";
    check_image(image, who);
    const ImageSurface& surf = options.surface;
    if (!std::isfinite(surf.iso) || (surf.label && !std::isfinite(*surf.label)))
        throw InvalidInput(std::string(who) + ": the iso value or label is not finite");
    if (!(options.voxel_size >= 0) || !std::isfinite(options.voxel_size))
        throw InvalidInput(std::string(who) + ": voxel_size " + num(options.voxel_size) + ": expected >= 0");

    // The frame: the image's axis directions; spacing per axis.
    std::array<double, 3> spacing{};
    Placement placement;
    bool aligned = true;
    for (int a = 0; a < 3; ++a) {
        spacing[a] = norm(image.axes[a]);
        Vec3d e{};
        (&e.x)[a] = 1.0;
        aligned = aligned && norm(image.axes[a] / spacing[a] - e) < 1e-9;
    }
    if (!aligned) placement = placement_from_axes(image.axes, image.origin);  // orthogonal to 1e-4 (checked)
    const double h = options.voxel_size > 0 ? options.voxel_size : std::min({spacing[0], spacing[1], spacing[2]});
    Grid g;
    g.voxel_size = h;
    g.origin = aligned ? image.origin : Vec3d{};
    g.placement = placement;
    bool resample = false;
    double total = 1;
    for (int a = 0; a < 3; ++a) {
        const double extent = (image.dims[a] - 1) * spacing[a];
        const double n = std::floor(extent / h + 1e-6) + 1;
        if (n > double(1 << 30)) throw InvalidInput(std::string(who) + ": voxel size " + num(h) + " is too small");
        g.dims[a] = int(n);
        total *= n;
        resample = resample || std::abs(spacing[a] - h) > 1e-6 * h;
    }
    if (total > kMaxSamples)
        throw InvalidInput(std::string(who) + ": a voxel size of " + num(h) + " makes a grid of " + num(total) +
                           " samples; raise the voxel size");

    // F on the grid, dense.
    const Field field{surf};
    const std::size_t nx = std::size_t(g.dims[0]), ny = std::size_t(g.dims[1]), nz = std::size_t(g.dims[2]);
    std::vector<float> F(nx * ny * nz);
    engine::for_samples(nz, [&](std::size_t k) {
        for (std::size_t j = 0; j < ny; ++j)
            for (std::size_t i = 0; i < nx; ++i) {
                float v;
                if (!resample) {
                    v = field(image.at(int(i), int(j), int(k)));
                } else {
                    // trilinear interpolation of F (not of the values: a label's indicator is interpolated)
                    const double c[3] = {double(i) * h / spacing[0], double(j) * h / spacing[1],
                                         double(k) * h / spacing[2]};
                    int i0[3];
                    double t[3];
                    for (int a = 0; a < 3; ++a) {
                        i0[a] = std::min(int(std::floor(c[a])), std::max(image.dims[a] - 2, 0));
                        t[a] = image.dims[a] > 1 ? std::clamp(c[a] - i0[a], 0.0, 1.0) : 0.0;
                    }
                    double acc = 0;
                    for (int dz = 0; dz < 2; ++dz)
                        for (int dy = 0; dy < 2; ++dy)
                            for (int dx = 0; dx < 2; ++dx) {
                                const double w =
                                    (dx ? t[0] : 1 - t[0]) * (dy ? t[1] : 1 - t[1]) * (dz ? t[2] : 1 - t[2]);
                                if (w == 0) continue;
                                const int ii = std::min(i0[0] + dx, image.dims[0] - 1);
                                const int jj = std::min(i0[1] + dy, image.dims[1] - 1);
                                const int kk = std::min(i0[2] + dz, image.dims[2] - 1);
                                acc += w * double(field(image.at(ii, jj, kk)));
                            }
                    v = float(acc);
                }
                F[i + nx * (j + ny * k)] = v;
            }
    });

    // Scale F to world units of distance near the surface: divide by the median |∇F| at the samples next
    // to a sign change (the engine's reinitialisation then bounds each by its axis crossings).
    const auto at = [&](std::size_t i, std::size_t j, std::size_t k) { return F[i + nx * (j + ny * k)]; };
    std::vector<float> grads;
    for (std::size_t k = 0; k < nz; ++k)
        for (std::size_t j = 0; j < ny; ++j)
            for (std::size_t i = 0; i < nx; ++i) {
                const float p = at(i, j, k);
                const std::size_t lo[3] = {i ? i - 1 : i, j ? j - 1 : j, k ? k - 1 : k};
                const std::size_t hi[3] = {std::min(i + 1, nx - 1), std::min(j + 1, ny - 1), std::min(k + 1, nz - 1)};
                const float n6[6] = {at(lo[0], j, k), at(hi[0], j, k), at(i, lo[1], k),
                                     at(i, hi[1], k), at(i, j, lo[2]), at(i, j, hi[2])};
                bool change = false;
                for (const float o : n6) change = change || ((o < 0) != (p < 0));
                if (!change) continue;
                double g2 = 0;
                for (int a = 0; a < 3; ++a) {
                    const double span = double((a == 0 ? hi[0] - lo[0] : a == 1 ? hi[1] - lo[1] : hi[2] - lo[2])) * h;
                    const double d = span > 0 ? (n6[2 * a + 1] - n6[2 * a]) / span : 0.0;
                    g2 += d * d;
                }
                if (g2 > 0) grads.push_back(float(std::sqrt(g2)));
            }
    if (grads.empty())
        throw InvalidInput(std::string(who) + ": the image holds no surface (" +
                           (surf.label ? "no sample, or every sample, has label " + num(*surf.label)
                                       : "every sample is on one side of the iso value " + num(surf.iso)) +
                           ")");
    std::nth_element(grads.begin(), grads.begin() + std::ptrdiff_t(grads.size() / 2), grads.end());
    const float scale = 1.0f / grads[grads.size() / 2];
    for (float& x : F) x *= scale;

    // Sparse volume: blocks near the surface (or straddling it) keep F; the others become tiles.
    Volume vol(g, engine::kHalfWidth);
    const float band = float(engine::kHalfWidth * h);
    for (int bk = 0; bk < vol.block_dims[2]; ++bk)
        for (int bj = 0; bj < vol.block_dims[1]; ++bj)
            for (int bi = 0; bi < vol.block_dims[0]; ++bi) {
                bool near = false, neg = false, pos = false;
                for (int z = bk * kBlockDim; z < std::min(int(nz), (bk + 1) * kBlockDim); ++z)
                    for (int y = bj * kBlockDim; y < std::min(int(ny), (bj + 1) * kBlockDim); ++y)
                        for (int x = bi * kBlockDim; x < std::min(int(nx), (bi + 1) * kBlockDim); ++x) {
                            const float v = at(std::size_t(x), std::size_t(y), std::size_t(z));
                            near = near || std::abs(v) < band;
                            (v < 0 ? neg : pos) = true;
                        }
                if (near || (neg && pos)) {
                    const std::int32_t b = vol.allocate_block(bi, bj, bk);
                    float* dst = vol.block_values(b);
                    for (int lz = 0; lz < kBlockDim; ++lz)
                        for (int ly = 0; ly < kBlockDim; ++ly)
                            for (int lx = 0; lx < kBlockDim; ++lx) {
                                const int x = bi * kBlockDim + lx, y = bj * kBlockDim + ly, z = bk * kBlockDim + lz;
                                if (x < int(nx) && y < int(ny) && z < int(nz))
                                    dst[Volume::local_index(lx, ly, lz)] =
                                        std::clamp(at(std::size_t(x), std::size_t(y), std::size_t(z)), -band, band);
                            }
                } else if (neg) {
                    vol.block_table[vol.table_index(bi, bj, bk)] = kBlockInside;
                }
            }
    std::vector<float>().swap(F);

    // A signed distance: the engine's band and reinitialisation.
    engine::Band b(vol);
    b.update_band();
    b.reinitialise(engine::kHalfWidth, engine::RunControl(progress, 1));
    b.write_back(vol);
    vol.check(who);
    return vol;
}

}  // namespace normalflow
