#pragma once
/// \file volume_sampler.h
/// Internal to lib/extract and lib/fit: φ and ∇φ of a volume at any world position, shared by fit_mesh_to_volume
/// and the surface attributes (vertex normals from the volume).

#include <cmath>

#include "core/vec.h"
#include "core/volume.h"

namespace normalflow::detail {

/// φ and ∇φ of a volume at any world position: trilinear interpolation of the samples and of their
/// central differences (so ∇φ is continuous across cells).
class VolumeSampler {
public:
    explicit VolumeSampler(const Volume& v) : v_(v), h_(v.grid.voxel_size) {}

    /// φ at p (world units); grad, when given, ∇φ there.
    double phi(const Vec3d& p, Vec3d* grad) const {
        const Vec3d g = v_.grid.index(p);
        const int i = int(std::floor(g.x)), j = int(std::floor(g.y)), k = int(std::floor(g.z));
        const double fx = g.x - i, fy = g.y - j, fz = g.z - k;
        double value = 0.0;
        Vec3d gradient(0, 0, 0);
        for (int c = 0; c < 8; ++c) {
            const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
            const double w = (dx ? fx : 1 - fx) * (dy ? fy : 1 - fy) * (dz ? fz : 1 - fz);
            const int a = i + dx, b = j + dy, d = k + dz;
            value += w * v_.value(a, b, d);
            if (grad)
                gradient = gradient + Vec3d(v_.value(a + 1, b, d) - v_.value(a - 1, b, d),
                                            v_.value(a, b + 1, d) - v_.value(a, b - 1, d),
                                            v_.value(a, b, d + 1) - v_.value(a, b, d - 1)) *
                                          (w / (2 * h_));
        }
        if (grad) *grad = gradient;
        return value;
    }

    /// Whether φ at p is the background (the sample cell has a corner outside the band).
    bool outside_band(const Vec3d& p) const {
        const Vec3d g = v_.grid.index(p);
        const int i = int(std::floor(g.x)), j = int(std::floor(g.y)), k = int(std::floor(g.z));
        for (int c = 0; c < 8; ++c)
            if (std::abs(v_.value(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1))) >= v_.background) return true;
        return false;
    }

    /// Whether the triangle (a, b, c) is turned over against the volume: its area vector and ∇φ at its centroid make
    /// more than 90°; false where the centroid is outside the band (faces_against_volume's test, and untangle's).
    bool turned_against(const Vec3d& a, const Vec3d& b, const Vec3d& c) const {
        const Vec3d centre = (a + b + c) / 3.0;
        if (outside_band(centre)) return false;
        Vec3d g;
        phi(centre, &g);
        return dot(cross(b - a, c - a), g) < 0;
    }

private:
    const Volume& v_;
    double h_;
};

/// The trilinear interpolation of a normal map at p, normalised, into n; false where a corner has no
/// normal (kNoNormal) or the blend vanishes.
inline bool sample_normal_map(const NormalMap& map, const Vec3d& p, Vec3d& n) {
    const Vec3d g = map[0].grid.index(p);
    const int i = int(std::floor(g.x)), j = int(std::floor(g.y)), k = int(std::floor(g.z));
    const double fx = g.x - i, fy = g.y - j, fz = g.z - k;
    double sum[3] = {0, 0, 0};
    for (int c = 0; c < 8; ++c) {
        const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
        const double w = (dx ? fx : 1 - fx) * (dy ? fy : 1 - fy) * (dz ? fz : 1 - fz);
        for (int a = 0; a < 3; ++a) {
            const float value = map[std::size_t(a)].value(i + dx, j + dy, k + dz);
            if (!(std::abs(value) < 1.5f)) return false;
            sum[a] += w * value;
        }
    }
    const Vec3d s(sum[0], sum[1], sum[2]);
    const double len = norm(s);
    if (!(len > 1e-6)) return false;
    n = s / len;
    return true;
}

}  // namespace normalflow::detail
