#include "metrics/compare.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/errors.h"
#include "core/mesh_report.h"
#include "sdf/closest_triangle.h"

namespace normalflow {

namespace {

constexpr double kDeg = 180.0 / std::numbers::pi;

Mesh welded_or_throw(const Mesh& m, const char* who, const char* which) {
    if (m.triangles.empty()) throw InvalidInput(std::string(who) + ": " + which + " mesh has no triangles");
    try {
        return weld_exact(m);
    } catch (const InvalidInput& e) {
        throw InvalidInput(std::string(who) + ": " + which + " mesh: " + e.what());
    }
}

/// Triangles binned by the grid cells their bounding boxes overlap (cell size h).
class TriangleGrid {
public:
    TriangleGrid(const Mesh& m, double h) : m_(m), h_(h) {
        for (std::uint32_t f = 0; f < m.triangles.size(); ++f) {
            const Tri& t = m.triangles[f];
            Box3d b;
            for (std::uint32_t v : t) b.extend(Vec3d(m.positions[v]));
            const Vec3i lo = cell(b.min), hi = cell(b.max);
            for (int z = lo.z; z <= hi.z; ++z)
                for (int y = lo.y; y <= hi.y; ++y)
                    for (int x = lo.x; x <= hi.x; ++x) cells_[key({x, y, z})].push_back(f);
        }
    }

    /// Faces with a point within distance r of p (r <= h), sorted by index.
    void near(const Vec3d& p, double r, std::vector<std::uint32_t>& out) const {
        out.clear();
        const Vec3i lo = cell(p - Vec3d{r, r, r}), hi = cell(p + Vec3d{r, r, r});
        for (int z = lo.z; z <= hi.z; ++z)
            for (int y = lo.y; y <= hi.y; ++y)
                for (int x = lo.x; x <= hi.x; ++x) {
                    auto it = cells_.find(key({x, y, z}));
                    if (it != cells_.end()) out.insert(out.end(), it->second.begin(), it->second.end());
                }
        std::sort(out.begin(), out.end());
        out.erase(std::unique(out.begin(), out.end()), out.end());
        std::erase_if(out, [&](std::uint32_t f) {
            const Tri& t = m_.triangles[f];
            const Vec3d q = closest_point_on_triangle(p, Vec3d(m_.positions[t[0]]), Vec3d(m_.positions[t[1]]),
                                                      Vec3d(m_.positions[t[2]]));
            return squared_norm(q - p) > r * r;
        });
    }

private:
    const Mesh& m_;
    double h_;
    std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> cells_;

    Vec3i cell(const Vec3d& p) const {
        return {int(std::floor(p.x / h_)), int(std::floor(p.y / h_)), int(std::floor(p.z / h_))};
    }
    static std::uint64_t key(const Vec3i& c) {
        auto u = [](int v) { return std::uint64_t(std::uint32_t(v + (1 << 20)) & 0x1fffffu); };
        return u(c.x) | (u(c.y) << 21) | (u(c.z) << 42);
    }
};

struct Sample {
    Vec3d p;
    Vec3d n1, n2;
    double length;
};

double relative_change(double cand, double ref) { return ref != 0 ? (cand - ref) / std::abs(ref) : 0.0; }

}  // namespace

CreasePreservation crease_preservation(const Mesh& candidate, const Mesh& reference, const CreaseOptions& opt) {
    const char* who = "crease_preservation";
    if (!(opt.angle_deg > 0 && opt.angle_deg < 180))
        throw InvalidInput(std::string(who) + ": angle " + std::to_string(opt.angle_deg) +
                           " out of range, expected (0, 180)");
    if (!(opt.radius_relative > 0) || !std::isfinite(opt.radius_relative))
        throw InvalidInput(std::string(who) + ": radius_relative " + std::to_string(opt.radius_relative) +
                           ", expected > 0");
    const Mesh ref = welded_or_throw(reference, who, "reference");
    const Mesh cand = welded_or_throw(candidate, who, "candidate");

    CreasePreservation c;
    c.angle_deg = opt.angle_deg;
    c.radius = opt.radius_relative * bounding_box(reference).diagonal();
    if (!(c.radius > 0)) throw InvalidInput(std::string(who) + ": reference mesh has a zero-size bounding box");
    const double cos_t = std::cos(opt.angle_deg / kDeg);

    // 1. Feature edges: (min, max, face) triples sorted; edges with exactly two faces.
    struct Half {
        std::uint32_t a, b, f;
    };
    std::vector<Half> halves;
    halves.reserve(3 * ref.triangles.size());
    std::vector<Vec3d> fn(ref.triangles.size());
    for (std::uint32_t f = 0; f < ref.triangles.size(); ++f) {
        const Tri& t = ref.triangles[f];
        const Vec3d n = face_area_vector(ref, t);
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || !(squared_norm(n) > 0)) continue;
        fn[f] = normalized(n);
        for (int k = 0; k < 3; ++k)
            halves.push_back({std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3]), f});
    }
    std::sort(halves.begin(), halves.end(), [](const Half& x, const Half& y) {
        return x.a != y.a ? x.a < y.a : (x.b != y.b ? x.b < y.b : x.f < y.f);
    });
    std::vector<Sample> samples;
    for (std::size_t i = 0; i < halves.size();) {
        std::size_t j = i;
        while (j < halves.size() && halves[j].a == halves[i].a && halves[j].b == halves[i].b) ++j;
        if (j - i == 2) {
            const Vec3d &n1 = fn[halves[i].f], &n2 = fn[halves[i + 1].f];
            if (dot(n1, n2) < cos_t) {
                const Vec3d a(ref.positions[halves[i].a]), b(ref.positions[halves[i].b]);
                const double len = norm(b - a);
                const auto pieces = std::max<std::size_t>(1, std::size_t(std::ceil(len / c.radius)));
                for (std::size_t k = 0; k < pieces; ++k)
                    samples.push_back(
                        {a + (b - a) * ((double(k) + 0.5) / double(pieces)), n1, n2, len / double(pieces)});
                ++c.feature_edges;
                c.feature_length += len;
            }
        }
        i = j;
    }
    c.samples = samples.size();
    if (samples.empty()) return c;

    // 2-4. Candidate sides around each sample.
    std::vector<Vec3d> cn(cand.triangles.size());
    for (std::size_t f = 0; f < cand.triangles.size(); ++f)
        cn[f] = face_area_vector(cand, cand.triangles[f]);  // 2·area·n
    const TriangleGrid grid(cand, c.radius);
    std::vector<double> angle(samples.size(), 0.0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, samples.size(), 64), [&](const auto& range) {
        std::vector<std::uint32_t> faces;
        for (std::size_t s = range.begin(); s != range.end(); ++s) {
            const Sample& q = samples[s];
            grid.near(q.p, c.radius, faces);
            Vec3d side1{}, side2{};
            bool has1 = false, has2 = false;
            for (std::uint32_t f : faces) {
                const Vec3d n = normalized(cn[f]);
                const double d1 = dot(n, q.n1), d2 = dot(n, q.n2);
                if (d1 <= 0 && d2 <= 0) continue;
                if (d1 >= d2) {
                    side1 += cn[f];
                    has1 = true;
                } else {
                    side2 += cn[f];
                    has2 = true;
                }
            }
            if (has1 && has2 && squared_norm(side1) > 0 && squared_norm(side2) > 0) {
                const double d = std::clamp(dot(normalized(side1), normalized(side2)), -1.0, 1.0);
                angle[s] = std::acos(d) * kDeg;
            }
        }
    });
    double weighted = 0;
    for (std::size_t s = 0; s < samples.size(); ++s) {
        weighted += angle[s] * samples[s].length;
        if (angle[s] > opt.angle_deg) c.preserved_length += samples[s].length;
    }
    c.fraction = c.feature_length > 0 ? std::min(1.0, c.preserved_length / c.feature_length) : 1.0;
    c.mean_angle_deg = c.feature_length > 0 ? weighted / c.feature_length : 0.0;
    return c;
}

std::string correspondence_mismatch(const Mesh& candidate, const Mesh& reference) {
    auto tri = [](const Tri& t) {
        std::string s(1, '(');  // not "(" + std::to_string(...): GCC 12 warns (-Wrestrict, a false positive)
        s += std::to_string(t[0]) + ", " + std::to_string(t[1]) + ", " + std::to_string(t[2]) + ")";
        return s;
    };
    if (candidate.positions.size() != reference.positions.size())
        return "candidate has " + std::to_string(candidate.positions.size()) + " vertices, reference " +
               std::to_string(reference.positions.size());
    if (candidate.triangles.size() != reference.triangles.size())
        return "candidate has " + std::to_string(candidate.triangles.size()) + " triangles, reference " +
               std::to_string(reference.triangles.size());
    for (std::size_t f = 0; f < candidate.triangles.size(); ++f)
        if (candidate.triangles[f] != reference.triangles[f])
            return "triangle " + std::to_string(f) + " differs: candidate " + tri(candidate.triangles[f]) +
                   ", reference " + tri(reference.triangles[f]);
    return {};
}

CorrespondenceErrors correspondence_errors(const Mesh& candidate, const Mesh& reference) {
    const char* who = "correspondence_errors";
    const std::string mismatch = correspondence_mismatch(candidate, reference);
    if (!mismatch.empty()) throw InvalidInput(std::string(who) + ": " + mismatch);
    if (reference.triangles.empty()) throw InvalidInput(std::string(who) + ": the meshes have no triangles");
    check_mesh(reference, std::string(who) + ": reference mesh");
    check_mesh(candidate, std::string(who) + ": candidate mesh");

    CorrespondenceErrors e;
    double angle_sum = 0;
    for (const Tri& t : reference.triangles) {
        const Vec3d n = face_area_vector(candidate, t), m = face_area_vector(reference, t);
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || !(squared_norm(n) > 0) || !(squared_norm(m) > 0)) {
            ++e.degenerate_faces;
            continue;
        }
        // atan2 of |n × m| and n · m: the angle without normalising, accurate near 0° and 180°.
        const double a = std::atan2(norm(cross(n, m)), dot(n, m)) * kDeg;
        angle_sum += a;
        e.max_face_angle_deg = std::max(e.max_face_angle_deg, a);
        ++e.faces;
    }
    e.mean_face_angle_deg = e.faces ? angle_sum / double(e.faces) : 0.0;

    double distance_sum = 0;
    for (std::size_t i = 0; i < reference.positions.size(); ++i) {
        const double d = norm(Vec3d(candidate.positions[i]) - Vec3d(reference.positions[i]));
        distance_sum += d;
        e.max_vertex_distance = std::max(e.max_vertex_distance, d);
    }
    e.vertices = reference.positions.size();
    e.mean_vertex_distance = e.vertices ? distance_sum / double(e.vertices) : 0.0;
    e.reference_diagonal = bounding_box(reference).diagonal();
    if (e.reference_diagonal > 0) {
        e.mean_vertex_distance_relative = e.mean_vertex_distance / e.reference_diagonal;
        e.max_vertex_distance_relative = e.max_vertex_distance / e.reference_diagonal;
    }
    return e;
}

MeshComparison compare_meshes(const Mesh& candidate, const Mesh& reference, const CompareOptions& opt) {
    const char* who = "compare_meshes";
    if (candidate.triangles.empty()) throw InvalidInput(std::string(who) + ": candidate mesh has no triangles");
    if (reference.triangles.empty()) throw InvalidInput(std::string(who) + ": reference mesh has no triangles");
    if (opt.correspondence) {  // before the costly part
        const std::string mismatch = correspondence_mismatch(candidate, reference);
        if (!mismatch.empty()) throw InvalidInput(std::string(who) + ": " + mismatch);
    }
    MeshComparison r;
    MeshReport rr, rc;
    try {
        rr = mesh_report(reference);
    } catch (const InvalidInput& e) {
        throw InvalidInput(std::string(who) + ": reference mesh: " + e.what());
    }
    try {
        rc = mesh_report(candidate);
    } catch (const InvalidInput& e) {
        throw InvalidInput(std::string(who) + ": candidate mesh: " + e.what());
    }
    r.distance = surface_distance(candidate, reference, opt.sampling);
    r.reference_diagonal = rr.bbox.diagonal();
    if (r.reference_diagonal > 0) {
        r.hausdorff_relative = r.distance.hausdorff / r.reference_diagonal;
        r.mean_relative = r.distance.mean / r.reference_diagonal;
        r.rms_relative = r.distance.rms / r.reference_diagonal;
    }
    r.area_reference = rr.area;
    r.area_candidate = rc.area;
    r.area_change = relative_change(rc.area, rr.area);
    r.volume_reference = rr.volume;
    r.volume_candidate = rc.volume;
    r.volume_change = relative_change(rc.volume, rr.volume);
    r.vertices_candidate = rc.referenced_vertices;
    r.faces_candidate = rc.faces;
    r.components_reference = rr.components;
    r.components_candidate = rc.components;
    r.closed_reference = rr.closed;
    r.closed_candidate = rc.closed;
    r.manifold_reference = rr.manifold;
    r.manifold_candidate = rc.manifold;
    if (!rr.closed || !rc.closed) r.warnings.push_back("a mesh is open: the volume change is only indicative");
    r.crease = crease_preservation(candidate, reference, opt.crease);
    if (opt.correspondence) {
        r.correspondence = correspondence_errors(candidate, reference);
        if (r.correspondence->degenerate_faces > 0)
            r.warnings.push_back(std::to_string(r.correspondence->degenerate_faces) +
                                 " degenerate triangles left out of the face-by-face normal angle");
    }
    return r;
}

}  // namespace normalflow
