// TetGen adapter. TETLIBRARY comes with the imported target normalflow_tetgen_lib.
#include "io/tetgen/tetmesh.h"

#include <tetgen.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "core/errors.h"
#include "core/mesh_report.h"
#include "io/util/atomic_file.h"
#include "io/util/isolate.h"
#ifdef NORMALFLOW_TETGEN_HAS_CGAL
#include "io/cgal/repair.h"
#endif

namespace normalflow {
namespace {

Vec3d sub(const Vec3d& a, const Vec3d& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec3d cross3(const Vec3d& a, const Vec3d& b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double dot3(const Vec3d& a, const Vec3d& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
double norm3(const Vec3d& a) { return std::sqrt(dot3(a, a)); }

/// Smallest of the six dihedral angles of tetrahedron (p0..p3), radians.
double min_dihedral(const Vec3d p[4]) {
    static constexpr int kEdges[6][4] = {{0, 1, 2, 3}, {0, 2, 1, 3}, {0, 3, 1, 2},
                                         {1, 2, 0, 3}, {1, 3, 0, 2}, {2, 3, 0, 1}};
    double best = 1e9;
    for (const auto& e : kEdges) {
        const Vec3d ab = sub(p[e[1]], p[e[0]]);
        const Vec3d n1 = cross3(ab, sub(p[e[2]], p[e[0]]));
        const Vec3d n2 = cross3(ab, sub(p[e[3]], p[e[0]]));
        const double c = dot3(n1, n2) / (norm3(n1) * norm3(n2));
        best = std::min(best, std::acos(std::clamp(c, -1.0, 1.0)));
    }
    return best;
}

/// The smallest angle between adjacent faces through the volume, radians, of a closed, consistently
/// oriented (outward) manifold surface: π − φ at a convex edge, π + φ at a concave one, φ the angle
/// between the two faces' normals.
double surface_min_angle(const Mesh& m) {
    std::vector<std::pair<std::uint64_t, std::uint32_t>> half;  // (edge key, face)
    half.reserve(3 * m.triangles.size());
    for (std::uint32_t f = 0; f < m.triangles.size(); ++f)
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t a = m.triangles[f][k], b = m.triangles[f][(k + 1) % 3];
            half.push_back({std::uint64_t(std::min(a, b)) << 32 | std::max(a, b), f});
        }
    std::sort(half.begin(), half.end());
    const auto normal = [&](std::uint32_t f) {
        const Tri& t = m.triangles[f];
        const Vec3d a(m.positions[t[0]]), b(m.positions[t[1]]), c(m.positions[t[2]]);
        const Vec3d n = cross3(sub(b, a), sub(c, a));
        const double l = norm3(n);
        return l > 0 ? Vec3d{n[0] / l, n[1] / l, n[2] / l} : n;
    };
    double best = 2 * std::numbers::pi;
    for (std::size_t i = 0; i + 1 < half.size(); ++i) {
        if (half[i].first != half[i + 1].first) continue;
        const std::uint32_t f1 = half[i].second, f2 = half[i + 1].second;
        const Vec3d n1 = normal(f1), n2 = normal(f2);
        const auto a = std::uint32_t(half[i].first >> 32);
        std::uint32_t c2 = m.triangles[f2][0];  // f2's corner off the edge
        for (const std::uint32_t v : m.triangles[f2])
            if (v != a && v != std::uint32_t(half[i].first)) c2 = v;
        const double phi = std::acos(std::clamp(dot3(n1, n2), -1.0, 1.0));
        const bool convex = dot3(n1, sub(Vec3d(m.positions[c2]), Vec3d(m.positions[a]))) <= 0;
        best = std::min(best, convex ? std::numbers::pi - phi : std::numbers::pi + phi);
    }
    return best;
}

void validate(const Mesh& m) {
    if (m.triangles.empty()) throw InvalidInput("tetrahedralize: the surface has no faces");
    const MeshReport r = mesh_report(m);  // also checks indices and finiteness
    if (!r.closed)
        throw InvalidInput("tetrahedralize: the surface is not closed (" + std::to_string(r.boundary_edges) +
                           " boundary edges); TetGen needs a closed surface");
    if (!r.manifold)
        throw InvalidInput("tetrahedralize: the surface is not manifold (" + std::to_string(r.non_manifold_edges) +
                           " non-manifold edges, " + std::to_string(r.non_manifold_vertices) +
                           " non-manifold vertices)");
    if (r.degenerate_faces > 0 || r.duplicate_faces > 0)
        throw InvalidInput("tetrahedralize: the surface has " + std::to_string(r.degenerate_faces) +
                           " degenerate and " + std::to_string(r.duplicate_faces) + " duplicate faces");
#ifdef NORMALFLOW_TETGEN_HAS_CGAL
    if (const std::size_t n = count_self_intersections(m); n > 0)
        throw InvalidInput("tetrahedralize: the surface intersects itself (" + std::to_string(n) + " pairs of faces)");
#endif
}

}  // namespace

TetMesh tetrahedralize(const Mesh& m_in, const TetmeshOptions& opt, TetmeshReport* report) {
    const auto t0 = std::chrono::steady_clock::now();
    if (!(opt.radius_edge >= 1.0) || !std::isfinite(opt.radius_edge))
        throw InvalidInput("tetrahedralize: radius_edge must be >= 1, got " + std::to_string(opt.radius_edge));
    if (!(opt.max_volume >= 0.0) || !std::isfinite(opt.max_volume))
        throw InvalidInput("tetrahedralize: max_volume must be >= 0");
    if (!(opt.min_dihedral_deg >= 0.0 && opt.min_dihedral_deg < 70.0))
        throw InvalidInput("tetrahedralize: min_dihedral_deg must be in [0, 70), got " +
                           std::to_string(opt.min_dihedral_deg));
    if (!(opt.max_dihedral_deg > 90.0 && opt.max_dihedral_deg < 180.0))
        throw InvalidInput("tetrahedralize: max_dihedral_deg must be in (90, 180), got " +
                           std::to_string(opt.max_dihedral_deg));
    if (opt.optimize_level < 0 || opt.optimize_level > 9)
        throw InvalidInput("tetrahedralize: optimize_level must be in 0..9, got " + std::to_string(opt.optimize_level));
    validate(m_in);
    const Mesh m = weld_exact(m_in);

    tetgenio in;
    in.firstnumber = 0;
    in.numberofpoints = static_cast<int>(m.positions.size());
    in.pointlist = new REAL[3 * m.positions.size()];
    for (std::size_t i = 0; i < m.positions.size(); ++i)
        for (int d = 0; d < 3; ++d) in.pointlist[3 * i + d] = m.positions[i][d];
    in.numberoffacets = static_cast<int>(m.triangles.size());
    in.facetlist = new tetgenio::facet[m.triangles.size()];
    in.facetmarkerlist = nullptr;
    for (std::size_t f = 0; f < m.triangles.size(); ++f) {
        tetgenio::facet& fc = in.facetlist[f];
        tetgenio::init(&fc);
        fc.numberofpolygons = 1;
        fc.polygonlist = new tetgenio::polygon[1];
        tetgenio::init(&fc.polygonlist[0]);
        fc.polygonlist[0].numberofvertices = 3;
        fc.polygonlist[0].vertexlist = new int[3];
        for (int k = 0; k < 3; ++k) fc.polygonlist[0].vertexlist[k] = static_cast<int>(m.triangles[f][k]);
    }
    char sw[128];
    if (opt.max_volume > 0)
        std::snprintf(sw, sizeof sw, "pzq%.6g/%.6g/%.6gO%da%.9gQ", opt.radius_edge, opt.min_dihedral_deg,
                      opt.max_dihedral_deg, opt.optimize_level, opt.max_volume);
    else
        std::snprintf(sw, sizeof sw, "pzq%.6g/%.6g/%.6gO%dQ", opt.radius_edge, opt.min_dihedral_deg,
                      opt.max_dihedral_deg, opt.optimize_level);
    // TetGen runs in a forked child (io/util/isolate.h): a crash on its error paths becomes an
    // IoError instead of ending the process. TetGen is single-threaded, as the child requires.
    const auto run = [&](const std::string& switches) {
        return run_isolated("tetrahedralize", [&] {
            tetgenio out;
            try {
                ::tetrahedralize(const_cast<char*>(switches.c_str()), &in, &out);
            } catch (...) {
                throw NumericalError("tetrahedralize: TetGen failed on the surface");
            }
            if (out.numberoftetrahedra <= 0) throw NumericalError("tetrahedralize: TetGen produced no tetrahedra");
            TetMesh tm;
            tm.points.resize(static_cast<std::size_t>(out.numberofpoints));
            for (std::size_t i = 0; i < tm.points.size(); ++i)
                tm.points[i] = Vec3d{out.pointlist[3 * i], out.pointlist[3 * i + 1], out.pointlist[3 * i + 2]};
            const int nc = out.numberofcorners;  // 4 (no second-order nodes requested)
            tm.tets.resize(static_cast<std::size_t>(out.numberoftetrahedra));
            for (std::size_t i = 0; i < tm.tets.size(); ++i)
                for (int k = 0; k < 4; ++k) tm.tets[i][k] = static_cast<std::uint32_t>(out.tetrahedronlist[nc * i + k]);
            ByteWriter w;
            w.put_array(tm.points);
            w.put_array(tm.tets);
            return w.take();
        });
    };
    // TetGen 1.5.0 merges adjacent faces within 0.1 degrees of coplanar (its facet_ang_tol 179.9) into
    // one facet. Surfaces extracted from a volume have thousands of such nearly, not exactly, coplanar
    // pairs; recovering the non-planar merged facets aborts in fillcavity ("searchtet.tet !=
    // midface->tet") or crashes (fandisk at 287k and 10k faces, a sphere at 461k). With Y (Keep, the
    // default without max_volume) the input triangles stay the boundary faces, unsplit and unmerged,
    // and the run succeeds; -a (max_volume) is then honoured only away from the surface. Without it
    // (Split) a failed run is retried with Y.
    const std::string plain = sw, with_y = plain.substr(0, 2) + "Y" + plain.substr(2);  // "pzY..."
    const bool keep = opt.surface == TetmeshOptions::Surface::Keep ||
                      (opt.surface == TetmeshOptions::Surface::Auto && !(opt.max_volume > 0));
    std::string used = keep ? with_y : plain;
    std::string bytes;
    try {
        bytes = run(used);
    } catch (const NumericalError&) {
        if (keep) throw;
        used = with_y;
        bytes = run(used);
    } catch (const IoError&) {
        if (keep) throw;
        used = with_y;
        bytes = run(used);
    }
    ByteReader reader(bytes, "tetrahedralize");
    TetMesh t;
    t.points = reader.get_array<Vec3d>();
    t.tets = reader.get_array<std::array<std::uint32_t, 4>>();
    for (const auto& tt : t.tets)
        for (std::uint32_t v : tt)
            if (v >= t.points.size())
                throw NumericalError("tetrahedralize: TetGen returned a tetrahedron index out of range");

    if (report) {
        TetmeshReport r;
        r.tetrahedra = t.tets.size();
        r.points = t.points.size();
        double mind = 1e9, vol = 0;
        for (const auto& tt : t.tets) {
            const Vec3d p[4] = {t.points[tt[0]], t.points[tt[1]], t.points[tt[2]], t.points[tt[3]]};
            vol += std::abs(dot3(sub(p[1], p[0]), cross3(sub(p[2], p[0]), sub(p[3], p[0])))) / 6.0;
            mind = std::min(mind, min_dihedral(p));
        }
        r.volume = vol;
        r.min_dihedral_deg = mind * 180.0 / std::numbers::pi;
        r.surface_volume = mesh_report(m).volume;
        r.surface_min_angle_deg = surface_min_angle(m) * 180.0 / std::numbers::pi;
        r.switches = used;
        r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        *report = r;
    }
    return t;
}

namespace {

std::string lower_ext(const std::string& p) {
    const auto dot = p.find_last_of('.');
    std::string e = dot == std::string::npos ? "" : p.substr(dot);
    for (auto& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return e;
}

void put(AtomicFile& f, const char* fmt, ...) __attribute__((format(printf, 2, 3)));
void put(AtomicFile& f, const char* fmt, ...) {
    char buf[256];
    va_list ap;
    va_start(ap, fmt);
    const int n = std::vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    f.write(buf, static_cast<std::size_t>(n));
}

}  // namespace

void write_tetmesh(const std::string& path, const TetMesh& t) {
    if (t.points.empty() || t.tets.empty()) throw InvalidInput("write_tetmesh: " + path + ": empty tetrahedral mesh");
    const std::string ext = lower_ext(path);
    if (ext == ".mesh") {
        AtomicFile f(path, "write_tetmesh");
        put(f, "MeshVersionFormatted 2\nDimension 3\nVertices\n%zu\n", t.points.size());
        for (const auto& p : t.points) put(f, "%.17g %.17g %.17g 0\n", p[0], p[1], p[2]);
        put(f, "Tetrahedra\n%zu\n", t.tets.size());
        for (const auto& q : t.tets) put(f, "%u %u %u %u 0\n", q[0] + 1, q[1] + 1, q[2] + 1, q[3] + 1);
        put(f, "End\n");
        f.commit();
    } else if (ext == ".vtu") {
        AtomicFile f(path, "write_tetmesh");
        put(f,
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
            "<UnstructuredGrid>\n<Piece NumberOfPoints=\"%zu\" NumberOfCells=\"%zu\">\n<Points>\n"
            "<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n",
            t.points.size(), t.tets.size());
        for (const auto& p : t.points) put(f, "%.17g %.17g %.17g\n", p[0], p[1], p[2]);
        put(f, "</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
        for (const auto& q : t.tets) put(f, "%u %u %u %u\n", q[0], q[1], q[2], q[3]);
        put(f, "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
        for (std::size_t i = 0; i < t.tets.size(); ++i) put(f, "%zu\n", 4 * (i + 1));
        put(f, "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
        for (std::size_t i = 0; i < t.tets.size(); ++i) put(f, "10\n");
        put(f, "</DataArray>\n</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
        f.commit();
    } else if (ext == ".node") {
        const std::string ele = path.substr(0, path.size() - 5) + ".ele";
        AtomicFile fn(path, "write_tetmesh");
        AtomicFile fe(ele, "write_tetmesh");
        put(fn, "%zu 3 0 0\n", t.points.size());
        for (std::size_t i = 0; i < t.points.size(); ++i)
            put(fn, "%zu %.17g %.17g %.17g\n", i, t.points[i][0], t.points[i][1], t.points[i][2]);
        put(fe, "%zu 4 0\n", t.tets.size());
        for (std::size_t i = 0; i < t.tets.size(); ++i)
            put(fe, "%zu %u %u %u %u\n", i, t.tets[i][0], t.tets[i][1], t.tets[i][2], t.tets[i][3]);
        fe.commit();
        fn.commit();
    } else {
        throw InvalidInput("write_tetmesh: " + path + ": unknown extension, expected .mesh, .vtu or .node");
    }
}

}  // namespace normalflow
