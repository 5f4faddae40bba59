// nf_check_surface FILE...: an evaluator of a written surface that shares no code with normalflow's own checks.
// Each file is read as the polygon soup it holds, vertex indices as written (no welding), made a CGAL
// Surface_mesh the way a user of CGAL would (orient_polygon_soup, which splits what is not manifold, then
// polygon_soup_to_polygon_mesh), and measured with CGAL's Polygon Mesh Processing: self_intersections (the
// pairs of faces that intersect other than at the vertices and edges they share), border edges, connected
// components, and the vertices the soup's orientation had to split (non-manifold). One JSON line per file:
//   {"file":..., "faces":..., "self_intersecting_pairs":..., "border_edges":..., "components":...,
//    "split_vertices":..., "degenerate_faces":...}
// The file is read with normalflow's reader only to get the positions and faces out of its format.
// Exit 1 when a file cannot be read.
#include <cstdio>
#include <exception>
#include <iterator>
#include <vector>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Polygon_mesh_processing/shape_predicates.h>
#include <CGAL/Surface_mesh.h>

#include "io/io.h"

namespace PMP = CGAL::Polygon_mesh_processing;
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using SM = CGAL::Surface_mesh<K::Point_3>;

int main(int argc, char** argv) {
    int status = 0;
    for (int i = 1; i < argc; ++i) {
        try {
            const normalflow::Mesh m = normalflow::read_mesh(argv[i]);
            std::vector<K::Point_3> points;
            for (const auto& p : m.positions) points.emplace_back(p.x, p.y, p.z);
            std::vector<std::vector<std::size_t>> faces;
            for (const auto& t : m.triangles) faces.push_back({t[0], t[1], t[2]});
            const std::size_t before = points.size();
            PMP::orient_polygon_soup(points, faces);
            SM sm;
            PMP::polygon_soup_to_polygon_mesh(points, faces, sm);
            std::vector<std::pair<SM::Face_index, SM::Face_index>> pairs;
            PMP::self_intersections(sm, std::back_inserter(pairs));
            std::size_t border = 0, degenerate = 0;
            for (auto h : sm.halfedges())
                if (sm.is_border(h)) ++border;
            for (auto f : sm.faces())
                if (PMP::is_degenerate_triangle_face(f, sm)) ++degenerate;
            auto component = sm.add_property_map<SM::Face_index, std::size_t>("f:c").first;
            const std::size_t components = PMP::connected_components(sm, component);
            std::printf(
                "{\"file\":\"%s\",\"faces\":%zu,\"self_intersecting_pairs\":%zu,\"border_edges\":%zu,"
                "\"components\":%zu,\"split_vertices\":%zu,\"degenerate_faces\":%zu}\n",
                argv[i], std::size_t(sm.number_of_faces()), pairs.size(), border, components, points.size() - before,
                degenerate);
        } catch (const std::exception& e) {
            std::fprintf(stderr, "nf_check_surface: %s: %s\n", argv[i], e.what());
            status = 1;
        }
    }
    return status;
}
