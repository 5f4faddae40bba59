#include "core/band_memory.h"

#include <cstdint>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace normalflow::detail {

#if defined(__linux__)
bool maps_huge_pages() noexcept { return true; }

void* map_huge(std::size_t bytes) {
    // Map one huge page more than asked and keep the aligned part: the kernel can back only
    // whole aligned 2 MiB ranges with huge pages.
    const std::size_t span = bytes + kHugePageBytes;
    void* raw = ::mmap(nullptr, span, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (raw == MAP_FAILED) throw std::bad_alloc();
    const auto base = reinterpret_cast<std::uintptr_t>(raw);
    const std::uintptr_t start = (base + kHugePageBytes - 1) & ~std::uintptr_t(kHugePageBytes - 1);
    if (start > base) ::munmap(raw, start - base);
    const std::uintptr_t end = start + bytes;
    if (base + span > end) ::munmap(reinterpret_cast<void*>(end), base + span - end);
#if defined(MADV_HUGEPAGE)
    ::madvise(reinterpret_cast<void*>(start), bytes, MADV_HUGEPAGE);  // advice only: may be refused
#endif
    return reinterpret_cast<void*>(start);
}

void unmap_huge(void* p, std::size_t bytes) noexcept { ::munmap(p, bytes); }
#else
bool maps_huge_pages() noexcept { return false; }
void* map_huge(std::size_t) { throw std::bad_alloc(); }
void unmap_huge(void*, std::size_t) noexcept {}
#endif

}  // namespace normalflow::detail
