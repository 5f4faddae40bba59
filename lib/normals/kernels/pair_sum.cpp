#include "normals/kernels/pair_sum.h"

#include "normals/kernels/exp_nonpositive.h"
#include "normals/kernels/row_kernel.h"

namespace normalflow::engine {

NF_ROW_KERNEL void pair_sum(const PairArrays& a, const PairSpan* spans, int count, const float q[3], const float rq[3],
                            float ks, float kr, float r2, float* __restrict acc) {
    const float qx = q[0], qy = q[1], qz = q[2];
    const float sx = rq[0], sy = rq[1], sz = rq[2];
    float ax[8], ay[8], az[8], aw[8];
    for (int l = 0; l < 8; ++l) ax[l] = ay[l] = az[l] = aw[l] = 0.0f;
    for (int k = 0; k < count; ++k) {
        const std::int64_t o = spans[k].begin;
        const int n = int(spans[k].n);
        const float* __restrict px = a.p[0] + o;
        const float* __restrict py = a.p[1] + o;
        const float* __restrict pz = a.p[2] + o;
        const float* __restrict rx = a.r[0] + o;
        const float* __restrict ry = a.r[1] + o;
        const float* __restrict rz = a.r[2] + o;
        const float* __restrict vx = a.v[0] + o;
        const float* __restrict vy = a.v[1] + o;
        const float* __restrict vz = a.v[2] + o;
        for (int j0 = 0; j0 < n; j0 += 8)
            for (int l = 0; l < 8; ++l) {
                const int j = j0 + l;
                const float dx = px[j] - qx, dy = py[j] - qy, dz = pz[j] - qz;
                const float d2 = (dx * dx + dy * dy) + dz * dz;
                const float ex = rx[j] - sx, ey = ry[j] - sy, ez = rz[j] - sz;
                const float c2 = (ex * ex + ey * ey) + ez * ez;
                const float e = exp_nonpositive(-(ks * d2 + kr * c2));
                const float w = d2 <= r2 ? e : 0.0f;
                ax[l] += w * vx[j];
                ay[l] += w * vy[j];
                az[l] += w * vz[j];
                aw[l] += w;
            }
    }
    for (int l = 0; l < 8; ++l) {
        acc[l] += ax[l];
        acc[8 + l] += ay[l];
        acc[16 + l] += az[l];
        acc[24 + l] += aw[l];
    }
}

}  // namespace normalflow::engine
