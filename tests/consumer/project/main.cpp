// A C++ application that links an installed normalflow: writes a tetrahedron and reads it back.
#include <normalflow/core/mesh.h>
#include <normalflow/core/mesh_report.h>
#include <normalflow/core/version.h>
#include <normalflow/io/io.h>
#include <normalflow/pipeline/pipeline.h>

#include <cstdio>
#include <string>

int main(int argc, char** argv) {
    if (argc < 2) return 2;
    normalflow::Mesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    normalflow::write_mesh(argv[1], m);
    const normalflow::Mesh r = normalflow::read_mesh(argv[1]);
    if (r.positions != m.positions || r.triangles != m.triangles) {
        std::printf("consumer: round trip differs\n");
        return 1;
    }
    // the whole pipeline links (every adapter the build has): a cube smoothed at a small resolution is closed
    normalflow::Mesh cube;
    cube.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    cube.triangles = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                      {2, 3, 7}, {2, 7, 6}, {1, 2, 6}, {1, 6, 5}, {0, 4, 7}, {0, 7, 3}};
    normalflow::PipelineOptions options;
    options.scan.resolution = 16;
    options.smooth.iterations = 1;
    const normalflow::PipelineResult s = normalflow::smooth_mesh(cube, options);
    if (s.mesh.triangles.empty() || normalflow::mesh_report(s.mesh).boundary_edges != 0) {
        std::printf("consumer: smooth_mesh gave %zu triangles\n", s.mesh.triangles.size());
        return 1;
    }
    static_assert(NORMALFLOW_VERSION >= 200, "the version macros come with the installed headers");
    if (std::string(normalflow::version()) != NORMALFLOW_VERSION_STRING) {
        std::printf("consumer: library %s, headers %s\n", normalflow::version(), NORMALFLOW_VERSION_STRING);
        return 1;
    }
    std::printf("consumer ok (normalflow %s)\n", normalflow::version());
    return 0;
}
