#include "io/render/render.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "core/errors.h"

namespace normalflow {

namespace {

constexpr double kPi = 3.14159265358979323846;

struct Frame {
    Vec3d right, up, forward;  // orthonormal; forward points from the eye into the scene
};

Frame camera_frame(const Camera& c, const char* who) {
    const Vec3d f = c.target - c.eye;
    if (!is_finite(c.eye) || !is_finite(c.target) || !is_finite(c.up) || !(squared_norm(f) > 0))
        throw InvalidInput(std::string(who) + ": camera eye and target must be finite and distinct");
    Frame fr;
    fr.forward = normalized(f);
    const Vec3d r = cross(fr.forward, c.up);
    if (!(norm(r) > 1e-9 * norm(c.up)) || !(squared_norm(c.up) > 0))
        throw InvalidInput(std::string(who) + ": camera up direction is zero or parallel to the view direction");
    fr.right = normalized(r);
    fr.up = cross(fr.right, fr.forward);
    return fr;
}

std::uint8_t to_byte(double v) {
    const double c = std::clamp(v, 0.0, 255.0);
    return static_cast<std::uint8_t>(std::lround(c));
}

}  // namespace

Camera camera_from_box(const Box3d& box, const Vec3d& view_direction, Projection projection, const Vec3d& up,
                       double margin) {
    if (box.empty() || !is_finite(box.min) || !is_finite(box.max))
        throw InvalidInput("camera_from_box: the bounding box is empty or not finite");
    if (!is_finite(view_direction) || !(squared_norm(view_direction) > 0))
        throw InvalidInput("camera_from_box: the view direction is zero or not finite");
    if (!(margin > 0) || !std::isfinite(margin)) throw InvalidInput("camera_from_box: margin must be > 0");
    const Vec3d v = normalized(view_direction);
    Camera c;
    c.projection = projection;
    c.target = box.center();
    double radius = 0.5 * box.diagonal();
    if (!(radius > 0)) radius = 1.0;  // a single point: any scale shows it
    c.up = up;
    if (!(squared_norm(up) > 0) || norm(cross(v, normalized(up))) < 1e-3)
        c.up = std::abs(v.z) < 0.9 ? Vec3d{0, 0, 1} : Vec3d{0, 1, 0};
    if (projection == Projection::Orthographic) {
        c.half_size = radius * margin;
        c.eye = c.target - v * (3.0 * radius * margin);
    } else {
        const double half = 0.5 * c.fov_deg * kPi / 180.0;
        c.eye = c.target - v * (radius * margin / std::sin(half));
    }
    return c;
}

Image render_mesh(const Mesh& m, const Camera& camera, const RenderOptions& opt) {
    static constexpr const char* who = "render_mesh";
    if (opt.width < 1 || opt.height < 1 || opt.width > 16384 || opt.height > 16384)
        throw InvalidInput("render_mesh: image size " + std::to_string(opt.width) + " x " + std::to_string(opt.height) +
                           " out of range, expected 1..16384 on each side");
    if (!(opt.ambient >= 0 && opt.ambient <= 1)) throw InvalidInput("render_mesh: ambient must be in [0, 1]");
    if (!is_finite(opt.light) || !(squared_norm(opt.light) > 0))
        throw InvalidInput("render_mesh: light direction is zero or not finite");
    const bool scalars = !opt.vertex_scalars.empty();
    if (scalars && opt.vertex_scalars.size() != m.positions.size())
        throw InvalidInput("render_mesh: " + std::to_string(opt.vertex_scalars.size()) + " vertex scalars, expected " +
                           std::to_string(m.positions.size()) + " (one per vertex)");
    if (scalars && !(opt.scalar_max > opt.scalar_min && std::isfinite(opt.scalar_min) && std::isfinite(opt.scalar_max)))
        throw InvalidInput("render_mesh: scalar range must be finite with scalar_max > scalar_min");
    const bool ortho = camera.projection == Projection::Orthographic;
    if (ortho && !(camera.half_size > 0 && std::isfinite(camera.half_size)))
        throw InvalidInput("render_mesh: orthographic camera half_size must be > 0");
    if (!ortho && !(camera.fov_deg > 0 && camera.fov_deg <= 170))
        throw InvalidInput("render_mesh: perspective camera fov_deg must be in (0, 170]");
    check_mesh(m, who);
    const Frame fr = camera_frame(camera, who);

    const int W = opt.width, H = opt.height;
    Image img(W, H, opt.background);
    if (m.triangles.empty()) return img;

    // Project every vertex: screen x right, y down (pixel units), depth d (smaller is nearer, linear in
    // screen space), w = perspective weight (1 orthographic, 1 / z perspective).
    const double short_side = 0.5 * std::min(W, H);
    const double scale =
        ortho ? short_side / camera.half_size : short_side / std::tan(0.5 * camera.fov_deg * kPi / 180.0);
    const std::size_t nv = m.positions.size();
    std::vector<double> sx(nv), sy(nv), depth(nv), wgt(nv);
    std::vector<char> in_front(nv, 1);
    const double near = 1e-9 * (norm(camera.target - camera.eye) + 1.0);
    for (std::size_t i = 0; i < nv; ++i) {
        const Vec3d q = Vec3d(m.positions[i]) - camera.eye;
        const double x = dot(q, fr.right), y = dot(q, fr.up), z = dot(q, fr.forward);
        if (ortho) {
            sx[i] = 0.5 * W + x * scale;
            sy[i] = 0.5 * H - y * scale;
            depth[i] = z;
            wgt[i] = 1.0;
        } else {
            if (!(z > near)) {
                in_front[i] = 0;
                continue;
            }
            sx[i] = 0.5 * W + scale * x / z;
            sy[i] = 0.5 * H - scale * y / z;
            depth[i] = -1.0 / z;
            wgt[i] = 1.0 / z;
        }
    }

    // Normals in camera coordinates so that the light (given in camera coordinates) is one dot product.
    auto to_camera = [&](const Vec3d& n) { return Vec3d{dot(n, fr.right), dot(n, fr.up), -dot(n, fr.forward)}; };
    const std::size_t nf = m.triangles.size();
    std::vector<Vec3d> face_n(nf);
    for (std::size_t f = 0; f < nf; ++f) face_n[f] = face_area_vector(m, m.triangles[f]);
    std::vector<Vec3d> vertex_n;
    if (opt.shading == Shading::Smooth) {
        vertex_n.assign(nv, Vec3d{});
        for (std::size_t f = 0; f < nf; ++f)
            for (std::uint32_t v : m.triangles[f]) vertex_n[v] += face_n[f];
        for (Vec3d& n : vertex_n) n = to_camera(normalized(n));
    }
    for (Vec3d& n : face_n) n = to_camera(normalized(n));
    const Vec3d light = normalized(opt.light);

    std::vector<double> zbuf(std::size_t(W) * std::size_t(H), std::numeric_limits<double>::infinity());
    const double inv_range = scalars ? 1.0 / (opt.scalar_max - opt.scalar_min) : 0.0;
    for (std::size_t f = 0; f < nf; ++f) {
        const Tri& t = m.triangles[f];
        if (!in_front[t[0]] || !in_front[t[1]] || !in_front[t[2]]) continue;
        const double x0 = sx[t[0]], y0 = sy[t[0]], x1 = sx[t[1]], y1 = sy[t[1]], x2 = sx[t[2]], y2 = sy[t[2]];
        const double area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0);
        if (!(std::abs(area) > 1e-12)) continue;
        const double inv_area = 1.0 / area;
        const int xa = std::max(0, int(std::ceil(std::min({x0, x1, x2}) - 0.5)));
        const int xb = std::min(W - 1, int(std::floor(std::max({x0, x1, x2}) - 0.5)));
        const int ya = std::max(0, int(std::ceil(std::min({y0, y1, y2}) - 0.5)));
        const int yb = std::min(H - 1, int(std::floor(std::max({y0, y1, y2}) - 0.5)));
        if (xa > xb || ya > yb) continue;
        const Vec3d& fn = face_n[f];
        for (int py = ya; py <= yb; ++py) {
            const double cy = py + 0.5;
            for (int px = xa; px <= xb; ++px) {
                const double cx = px + 0.5;
                // Barycentric coordinates from the three edge functions, normalised by the signed area,
                // so both windings are accepted; >= 0 includes the edges (no cracks between neighbours).
                const double b0 = ((x1 - cx) * (y2 - cy) - (x2 - cx) * (y1 - cy)) * inv_area;
                const double b1 = ((x2 - cx) * (y0 - cy) - (x0 - cx) * (y2 - cy)) * inv_area;
                const double b2 = 1.0 - b0 - b1;
                if (b0 < 0 || b1 < 0 || b2 < 0) continue;
                const double d = b0 * depth[t[0]] + b1 * depth[t[1]] + b2 * depth[t[2]];
                const std::size_t pix = std::size_t(py) * std::size_t(W) + std::size_t(px);
                if (!(d < zbuf[pix])) continue;
                zbuf[pix] = d;
                // Perspective-correct weights.
                double p0 = b0 * wgt[t[0]], p1 = b1 * wgt[t[1]], p2 = b2 * wgt[t[2]];
                const double ps = p0 + p1 + p2;
                p0 /= ps;
                p1 /= ps;
                p2 /= ps;
                Vec3d n = fn;
                if (opt.shading == Shading::Smooth) {
                    const Vec3d s = vertex_n[t[0]] * p0 + vertex_n[t[1]] * p1 + vertex_n[t[2]] * p2;
                    if (squared_norm(s) > 1e-24) n = normalized(s);
                }
                const double lambert = std::abs(dot(n, light));
                const double shade = opt.ambient + (1.0 - opt.ambient) * lambert;
                Rgb8 base = opt.base_color;
                if (scalars) {
                    const double v =
                        p0 * opt.vertex_scalars[t[0]] + p1 * opt.vertex_scalars[t[1]] + p2 * opt.vertex_scalars[t[2]];
                    base = opt.over_color && v > opt.scalar_max
                               ? *opt.over_color
                               : map_color(opt.color_map, (v - opt.scalar_min) * inv_range);
                }
                img.set(px, py, {to_byte(base.r * shade), to_byte(base.g * shade), to_byte(base.b * shade)});
            }
        }
    }
    return img;
}

}  // namespace normalflow
