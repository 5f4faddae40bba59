#include "io/meshopt/decimate.h"

#include <meshoptimizer.h>

#include <chrono>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "core/errors.h"

namespace normalflow::meshopt {

static_assert(sizeof(Vec3f) == 3 * sizeof(float), "meshopt reads positions as packed float triples");
static_assert(sizeof(Tri) == 3 * sizeof(unsigned int), "meshopt reads triangles as packed index triples");

DecimateReport decimate_mesh(Mesh& m, const DecimateOptions& opt) {
    const auto t0 = std::chrono::steady_clock::now();
    check_mesh(m, "decimate_mesh");
    if (opt.target_faces < 4)
        throw InvalidInput("decimate_mesh: target_faces must be >= 4, got " + std::to_string(opt.target_faces));
    if (m.triangles.empty()) throw InvalidInput("decimate_mesh: empty mesh (no triangles)");
    DecimateReport rep;
    rep.faces_before = m.triangles.size();
    rep.vertices_before = m.positions.size();

    const std::size_t nv = m.positions.size();
    const auto* indices = reinterpret_cast<const unsigned int*>(m.triangles.data());
    const std::size_t index_count = m.triangles.size() * 3;
    std::vector<unsigned int> out(index_count);
    std::size_t kept = index_count;
    if (m.triangles.size() > opt.target_faces) {
        float rel_error = 0.0f;
        // No error limit: the face count is the goal (meshopt's target_error is relative to the extent).
        kept = meshopt_simplify(out.data(), indices, index_count, &m.positions[0].x, nv, sizeof(Vec3f),
                                opt.target_faces * 3, std::numeric_limits<float>::max(),
                                opt.lock_border ? unsigned(meshopt_SimplifyLockBorder) : 0u, &rel_error);
        rep.error = double(rel_error) * double(meshopt_simplifyScale(&m.positions[0].x, nv, sizeof(Vec3f)));
    } else {
        out.assign(indices, indices + index_count);
    }
    out.resize(kept);

    m.triangles.resize(kept / 3);
    for (std::size_t f = 0; f < m.triangles.size(); ++f)
        for (int c = 0; c < 3; ++c) m.triangles[f][c] = out[3 * f + std::size_t(c)];
    remove_unreferenced_vertices(m);

    rep.faces_after = m.triangles.size();
    rep.vertices_after = m.positions.size();
    rep.reached_target = rep.faces_after <= opt.target_faces;
    rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return rep;
}

}  // namespace normalflow::meshopt
