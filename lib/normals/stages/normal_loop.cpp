#include "normals/stages/normal_loop.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <utility>
#include <vector>

#include "band/gather.h"
#include "band/iterate.h"
#include "normals/kernels/masked_block_sum.h"
#include "normals/kernels/row_mask.h"
#include "normals/kernels/update_row.h"

namespace normalflow::engine {

void NormalLoop::init_normals(StageContext& c) {
    Band& band = c.band;
    const Samples& phi = band.phi();
    Field3& normals = band.work().normals;
    band.for_blocks(band.all_blocks(), 1, [&](std::size_t, std::int32_t b, Scratch& s) {
        const Neighbourhood& n = band.neighbourhood(std::size_t(b));
        float* P = s.at(0);
        gather_phi(n, phi, P);
        const std::size_t base = std::size_t(b) * kBlockVoxels;
        for (int z = 0; z < kBlockDim; ++z)
            for (int y = 0; y < kBlockDim; ++y)
                for (int x = 0; x < kBlockDim; ++x) {
                    const int q = lidx(x, y, z);
                    const float gx = 0.5f * (P[q + 1] - P[q - 1]);
                    const float gy = 0.5f * (P[q + L] - P[q - L]);
                    const float gz = 0.5f * (P[q + L2] - P[q - L2]);
                    const float gn = std::sqrt(gx * gx + gy * gy + gz * gz);
                    const float inv = gn > 1e-6f ? 1.0f / gn : 0.0f;
                    const std::size_t i = base + std::size_t(bidx(x, y, z));
                    normals[0][i] = gx * inv;
                    normals[1][i] = gy * inv;
                    normals[2][i] = gz * inv;
                }
    });
}

void NormalLoop::cache_phi(StageContext& c) {
    const Band& bd = c.band;
    const std::vector<std::int32_t>& active = bd.active();
    pad_phi_.resize(active.size() * std::size_t(L3));
    row_band_.resize(active.size() * std::size_t(kRowFlags));
    const float band = c.opt.active_band;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, active.size(), 16),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t k = r.begin(); k != r.end(); ++k) {
                              float* P = pad_phi_.data() + k * L3;
                              gather_phi(bd.neighbourhood(std::size_t(active[k])), bd.phi(), P);
                              std::uint8_t* rows = row_band_.data() + k * kRowFlags;
                              for (int a = 0; a < 3; ++a) {
                                  const int sa = kStride[a];
                                  int lo[3] = {0, 0, 0};
                                  lo[a] = -1;
                                  for (int z = lo[2]; z < kBlockDim; ++z)
                                      for (int y = lo[1]; y < kBlockDim; ++y) {
                                          const int q0 = lidx(lo[0], y, z);
                                          bool any = false;  // a face of the row touches the band
                                          for (int j = 0; j < kBlockDim - lo[0]; ++j)
                                              any |= !(std::abs(P[q0 + j]) > band && std::abs(P[q0 + j + sa]) > band);
                                          rows[row_flag(a, y, z)] = any;
                                      }
                              }
                          }
                      });
}

double NormalLoop::step(StageContext& c, Field3& src, Field3& dst, FaceWeight cond, bool update, const PaddedFaces* g) {
    const Band& bd = c.band;
    const std::vector<std::int32_t>& active = bd.active();
    const std::uint8_t* mask = bd.mask();
    std::vector<double> energy(active.size(), 0.0);
    std::atomic<bool> bad{false};
    const float dt = std::min(c.opt.normal_dt, kMaxDt);
    const float inv2mu2 = 1.0f / (2.0f * c.opt.mu * c.opt.mu);
    const float band = c.opt.active_band;
    bd.for_blocks(active, 13, [&](std::size_t k, std::int32_t b, Scratch& s) {
        const Neighbourhood& n = bd.neighbourhood(std::size_t(b));
        const float* P = pad_phi_.data() + k * L3;
        float* N[3] = {s.at(0), s.at(1), s.at(2)};
        float* F[3][3] = {{s.at(3), s.at(4), s.at(5)}, {s.at(6), s.at(7), s.at(8)}, {s.at(9), s.at(10), s.at(11)}};
        float* E = s.at(12);  // energy density of the faces of one axis
        gather_n(n, src, N[0], N[1], N[2]);
        const std::size_t base = std::size_t(b) * kBlockVoxels;
        const std::uint8_t* M = mask + base;
        const std::uint8_t* rows = row_band_.data() + k * kRowFlags;
        double e = 0.0;
        for (int a = 0; a < 3; ++a) {
            int lo[3] = {0, 0, 0};
            lo[a] = -1;
            auto faces = [&](int q0, int count, int nrows) {
                switch (cond) {
                    case FaceWeight::One:
                        face_rows<FaceWeight::One>(a, P, N[0], nullptr, q0, count, nrows, band, inv2mu2, F[a][0], E);
                        break;
                    case FaceWeight::Frozen:
                        face_rows<FaceWeight::Frozen>(a, P, N[0], g[a].data() + k * L3, q0, count, nrows, band, inv2mu2,
                                                      F[a][0], E);
                        break;
                    case FaceWeight::Live:
                        face_rows<FaceWeight::Live>(a, P, N[0], nullptr, q0, count, nrows, band, inv2mu2, F[a][0], E);
                        break;
                }
            };
            // Rows whose faces all lie outside the band are not computed: the divergence below
            // reads only the faces of active samples, which lie in the band.
            if (a == 0) {
                // x faces, 9 per row (x = −1 … 7): the flagged rows of a z plane in one run over
                // the padded buffer, rounded up to whole vectors, instead of a row of 8 plus a
                // scalar ninth face each. The extra faces (x = 8, and unflagged rows inside the
                // run) lie in the buffer and are never read.
                for (int z = 0; z < kBlockDim; ++z) {
                    const auto [y0, y1] = row_span(0, [&](int y) { return rows[row_flag(0, y, z)] != 0; });
                    if (y1 < y0) continue;
                    const int count = ((y1 - y0) * L + (kBlockDim + 1) + (kBlockDim - 1)) / kBlockDim * kBlockDim;
                    faces(lidx(-1, y0, z), count, 1);
                }
            } else {
                // y and z faces, 8 per row: the flagged rows of a z plane in one call, row by
                // row (unflagged rows inside the span are computed and never read), so that
                // the rows' long dependency chains (division, exp) overlap.
                for (int z = lo[2]; z < kBlockDim; ++z) {
                    const auto [y0, y1] = row_span(lo[1], [&](int y) { return rows[row_flag(a, y, z)] != 0; });
                    if (y1 >= y0) faces(lidx(0, y0, z), kBlockDim, y1 - y0 + 1);
                }
            }
            // energy of the faces owned by the active samples of this block (in band: computed)
            e += masked_block_sum(E, M);
        }
        energy[k] = e;
        if (!update) return;
        // N ← normalize(N + dt (I − NNᵀ) ∇·F) at the active samples; the rest keep N. Rows of
        // 8, branch-free (selects), so that the loop vectorises.
        int nonfinite = 0;
        auto update_rows = [&](int y, int z, int count) {
            const int q0 = lidx(0, y, z);
            const std::size_t i0 = base + std::size_t(bidx(0, y, z));
            nonfinite |= update_row(F[0][0] + q0, F[0][1] + q0, F[0][2] + q0, F[1][0] + q0, F[1][1] + q0, F[1][2] + q0,
                                    F[2][0] + q0, F[2][1] + q0, F[2][2] + q0, N[0] + q0, N[1] + q0, N[2] + q0,
                                    mask + i0, dt, count, dst[0].data() + i0, dst[1].data() + i0, dst[2].data() + i0);
        };
        // Row by row over the span of a z plane's rows with active samples, in one call (see
        // face_row). A row inside the span without any gets dst = N, which dst already holds
        // there (see run).
        for (int z = 0; z < kBlockDim; ++z) {
            const auto [y0, y1] = row_span(0, [&](int y) { return any_in_row(M + bidx(0, y, z)); });
            if (y1 >= y0) update_rows(y0, z, y1 - y0 + 1);
        }
        if (nonfinite) bad = true;
    });
    if (bad) c.ctl.fail("normal in the normal loop");
    double sum = 0.0;
    for (const double e : energy) sum += e;
    return sum;
}

void NormalLoop::run(StageContext& c, FaceWeight w, const PaddedFaces* g) {
    Field3& n = c.band.work().normals;
    Field3& n2 = c.band.work().normals_next;
    copy_fields(n, n2);
    std::vector<double> gs;
    for (int s = 0; s < c.opt.normal_steps; ++s) {
        gs.push_back(step(c, n, n2, w, true, g));
        std::swap(n, n2);
        c.ctl.tick(0.5 * double(s + 1) / c.opt.normal_steps);
    }
    gs.push_back(step(c, n, n2, w, false, g));
    c.record().normal_energy = std::move(gs);
}

void NormalLoop::prepare(StageContext& c) {
    init_normals(c);
    cache_phi(c);
}

}  // namespace normalflow::engine
