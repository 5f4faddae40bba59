#pragma once
// Test support: a sphere with every per-vertex attribute, and attribute comparisons that allow for
// the reordering and quantisation of lossy formats.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numbers>
#include <vector>

#include "core/mesh.h"
#include "sdf/sdf_test_meshes.h"

namespace normalflow::test {

/// An icosphere of radius 1 whose normals are its unit positions, whose colours cover the whole
/// 0..255 range (dark shades included) and whose texture coordinates are longitude and latitude in
/// [0, 1] (no seam: a vertex on the date line keeps u of its own side).
inline Mesh attributed_sphere(int levels = 2) {
    Mesh m = icosphere(1.0, levels);
    const std::size_t n = m.positions.size();
    for (std::size_t i = 0; i < n; ++i) {
        const Vec3f p = m.positions[i];
        const float len = std::sqrt(dot(p, p));
        m.normals.push_back(p / len);
        m.colors.push_back(Rgba8{std::uint8_t(i * 7 % 256), std::uint8_t(i * 13 % 256), std::uint8_t(255 - i % 256),
                                 std::uint8_t(128 + i % 128)});
        const double u = 0.5 + std::atan2(double(p.y), double(p.x)) / (2 * std::numbers::pi);
        const double v = 0.5 + std::asin(std::clamp(double(p.z) / len, -1.0, 1.0)) / std::numbers::pi;
        m.texcoords.push_back(TexCoord{float(u), float(v)});
    }
    return m;
}

/// Largest differences between the attributes of b and those of a, matching each vertex of b to the
/// vertex of a at the same place (lossy formats reorder and quantise; b's vertices must each be
/// within `position_tolerance` of one of a's).
struct AttributeErrors {
    double position = 0, normal_deg = 0, color = 0, texcoord = 0;
};

inline AttributeErrors attribute_errors(const Mesh& a, const Mesh& b, double position_tolerance) {
    AttributeErrors e;
    EXPECT_EQ(a.has_normals(), b.has_normals());
    EXPECT_EQ(a.has_colors(), b.has_colors());
    EXPECT_EQ(a.has_texcoords(), b.has_texcoords());
    for (std::size_t j = 0; j < b.positions.size(); ++j) {
        std::size_t best = 0;
        double d_best = 1e300;
        for (std::size_t i = 0; i < a.positions.size(); ++i) {
            const Vec3f d = a.positions[i] - b.positions[j];
            const double d2 = double(dot(d, d));
            if (d2 < d_best) d_best = d2, best = i;
        }
        const double d = std::sqrt(d_best);
        EXPECT_LE(d, position_tolerance) << "vertex " << j << " is far from every input vertex";
        e.position = std::max(e.position, d);
        if (a.has_normals() && b.has_normals()) {
            const Vec3d na(a.normals[best]), nb(b.normals[j]);
            // atan2 of |cross| and dot: exact near 0 degrees, where acos of a rounded cosine is not
            const double deg = std::atan2(norm(cross(na, nb)), dot(na, nb)) * 180 / std::numbers::pi;
            e.normal_deg = std::max(e.normal_deg, deg);
        }
        if (a.has_colors() && b.has_colors())
            for (std::size_t k = 0; k < 4; ++k)
                e.color = std::max(e.color, std::abs(double(a.colors[best][k]) - double(b.colors[j][k])));
        if (a.has_texcoords() && b.has_texcoords())
            for (std::size_t k = 0; k < 2; ++k)
                e.texcoord = std::max(e.texcoord, std::abs(double(a.texcoords[best][k]) - double(b.texcoords[j][k])));
    }
    return e;
}

}  // namespace normalflow::test
