#include "normals/kernels/masked_block_sum.h"

#include <cstring>

#include "normals/kernels/row_kernel.h"
#include "normals/kernels/row_mask.h"

namespace normalflow::engine {

NF_ROW_KERNEL double masked_block_sum(const float* __restrict E, const std::uint8_t* __restrict m) {
    using v8f = float __attribute__((vector_size(32)));
    using v8i = std::int32_t __attribute__((vector_size(32)));
    v8f acc = {};
    for (int z = 0; z < kBlockDim; ++z)
        for (int y = 0; y < kBlockDim; ++y) {
            v8f e;
            std::memcpy(&e, E + lidx(0, y, z), sizeof e);
            const std::uint8_t* r = m + bidx(0, y, z);
            const v8i mi = {r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7]};
            const v8i keep = mi != 0;  // lanes of all ones or zeros
            acc += reinterpret_cast<v8f>(reinterpret_cast<v8i>(e) & keep);
        }
    return double(((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7])));
}

}  // namespace normalflow::engine
