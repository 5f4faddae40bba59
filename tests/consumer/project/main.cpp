// A C++ application that links an installed normalflow: writes a tetrahedron and reads it back.
#include <normalflow/core/mesh.h>
#include <normalflow/core/version.h>
#include <normalflow/io/io.h>

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
    static_assert(NORMALFLOW_VERSION >= 200, "the version macros come with the installed headers");
    if (std::string(normalflow::version()) != NORMALFLOW_VERSION_STRING) {
        std::printf("consumer: library %s, headers %s\n", normalflow::version(), NORMALFLOW_VERSION_STRING);
        return 1;
    }
    std::printf("consumer ok (normalflow %s)\n", normalflow::version());
    return 0;
}
