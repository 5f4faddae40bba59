#include "core/mesh.h"

#include <string>

#include "core/errors.h"

namespace normalflow {

void check_mesh(const Mesh& m, std::string_view who) {
    const std::size_t n = m.positions.size();
    for (std::size_t f = 0; f < m.triangles.size(); ++f)
        for (const std::uint32_t v : m.triangles[f])
            if (v >= n)
                throw InvalidInput(std::string(who) + ": triangle " + std::to_string(f) + " has vertex index " +
                                   std::to_string(v) + ", expected < " + std::to_string(n));
    for (std::size_t i = 0; i < n; ++i)
        if (!is_finite(m.positions[i]))
            throw InvalidInput(std::string(who) + ": vertex " + std::to_string(i) + " has a non-finite coordinate");
}

}  // namespace normalflow
