#include "build_licence.h"

#include <vector>

#include "core/version.h"

namespace normalflow::cli {

namespace {

struct Library {
    const char* name;
    const char* licence;
    const char* use;
};

/// The libraries this build links, as CMake's NORMALFLOW_WITH_* options chose them (apps/normalflow/CMakeLists.txt).
std::vector<Library> linked_libraries() {
    std::vector<Library> l{{"oneTBB", "Apache-2.0", "threads"}, {"CLI11", "BSD-3-Clause", "the command line"}};
#if NORMALFLOW_HAS_ZLIB
    l.push_back({"zlib", "Zlib", "gzip in NRRD and NIfTI, PNG pictures"});
#endif
#if NORMALFLOW_HAS_OPENVDB
    l.push_back({"OpenVDB", "MPL-2.0", ".vdb volumes"});
#endif
#if NORMALFLOW_HAS_DRACO
    l.push_back({"Draco", "Apache-2.0", ".drc, glTF/GLB"});
#endif
#if NORMALFLOW_HAS_OPENMESH
    l.push_back({"OpenMesh", "BSD-3-Clause", "Taubin, Laplacian, bilateral baselines"});
#endif
#if NORMALFLOW_HAS_MESHOPTIMIZER
    l.push_back({"meshoptimizer", "MIT", "--decimator meshoptimizer"});
#endif
#if NORMALFLOW_HAS_CGAL
    l.push_back({"CGAL", "GPL-3.0-or-later", "repair, AABB distances, self-intersections, edge collapse"});
#endif
#if NORMALFLOW_HAS_TETGEN
    l.push_back({"TetGen", "AGPL-3.0-or-later", "tetmesh"});
#endif
    return l;
}

}  // namespace

std::string version_text() {
    std::string t = std::string("normalflow ") + version() + " (normalflow's own code: Apache-2.0)\nlinked:\n";
    std::string strongest = "Apache-2.0", because;
    for (const Library& l : linked_libraries()) {
        t += std::string("  ") + l.name + " (" + l.licence + "): " + l.use + "\n";
        const std::string lic = l.licence;
        if (lic == "AGPL-3.0-or-later" || (lic == "GPL-3.0-or-later" && strongest != "AGPL-3.0-or-later")) {
            strongest = lic;
            because = l.name;
        }
    }
    t += "this build of the tool: " + strongest;
    t += because.empty() ? " (every library it links is permissive)"
                         : " (it links " + because +
                               "; -DNORMALFLOW_WITH_TETGEN=OFF -DNORMALFLOW_WITH_CGAL=OFF build an "
                               "Apache-2.0 tool)";
    return t;
}

}  // namespace normalflow::cli
