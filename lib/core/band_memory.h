#pragma once
/// \file band_memory.h
/// Allocators for the engine's band-sized work arrays (φ, the normals, their ping-pong buffers).
///
/// Such an array is hundreds of MiB at resolution 512 and is first written by parallel stages. In
/// 4 KiB pages every first write to a page is a fault, and in a virtual machine a fault costs
/// microseconds: at resolution 256 the engine took ~135,000 of them per run, 0.9 s of system
/// time on 2 cores. HugePageAllocator maps an allocation of 2 MiB or more on its own, aligned to
/// 2 MiB, and asks the kernel for transparent huge pages there (Linux madvise(MADV_HUGEPAGE),
/// which a system with THP set to "madvise", the default of many distributions, needs): then a
/// fault brings in 2 MiB. Where huge pages are off or unavailable the mapping still works, in
/// 4 KiB pages. Smaller allocations, and other systems, use std::allocator.
/// The contents are those of any allocation: the values the engine computes do not depend on it.

#include <cstddef>
#include <cstring>
#include <memory>
#include <new>
#include <utility>

namespace normalflow::detail {

/// Maps `bytes` (a multiple of kHugePageBytes) aligned to kHugePageBytes, advised for huge pages;
/// throws std::bad_alloc. unmap_huge releases it.
void* map_huge(std::size_t bytes);
void unmap_huge(void* p, std::size_t bytes) noexcept;
/// Whether this build maps large allocations itself (Linux), else std::allocator serves them.
bool maps_huge_pages() noexcept;

inline constexpr std::size_t kHugePageBytes = std::size_t(2) << 20;

/// std::allocator, except that an allocation of kHugePageBytes or more is mapped with map_huge.
template <class T>
struct HugePageAllocator {
    using value_type = T;
    HugePageAllocator() = default;
    template <class U>
    HugePageAllocator(const HugePageAllocator<U>&) noexcept {}

    static std::size_t mapped_bytes(std::size_t n) {
        const std::size_t bytes = n * sizeof(T);
        return (bytes + kHugePageBytes - 1) / kHugePageBytes * kHugePageBytes;
    }
    static bool mapped(std::size_t n) { return maps_huge_pages() && n * sizeof(T) >= kHugePageBytes; }

    T* allocate(std::size_t n) {
        if (n > std::size_t(-1) / sizeof(T)) throw std::bad_alloc();
        if (mapped(n)) return static_cast<T*>(map_huge(mapped_bytes(n)));
        return std::allocator<T>().allocate(n);
    }
    void deallocate(T* p, std::size_t n) noexcept {
        if (mapped(n))
            unmap_huge(p, mapped_bytes(n));
        else
            std::allocator<T>().deallocate(p, n);
    }
    template <class U>
    bool operator==(const HugePageAllocator<U>&) const noexcept {
        return true;
    }
};

/// HugePageAllocator whose resize() leaves new elements uninitialised (default-initialised): for
/// arrays that every stage writes before it reads them. A fresh allocation reads as zeros, though:
/// mapped ones are fresh pages, and the smaller ones, which malloc may serve from memory freed by other
/// data, are cleared. Some stages read samples they never wrote, with a zero weight; reused memory whose
/// bits happened to be a NaN made their result depend on what the process had done before (issue 20's
/// study: 6.60° and 6.76° for the same run of twelve_imp0.5).
template <class T>
struct NoInitAllocator : HugePageAllocator<T> {
    T* allocate(std::size_t n) {
        T* p = HugePageAllocator<T>::allocate(n);
        if (!HugePageAllocator<T>::mapped(n)) std::memset(static_cast<void*>(p), 0, n * sizeof(T));
        return p;
    }
    template <class U>
    struct rebind {
        using other = NoInitAllocator<U>;
    };
    NoInitAllocator() = default;
    template <class U>
    NoInitAllocator(const NoInitAllocator<U>&) noexcept {}
    template <class U>
    void construct(U* p) noexcept {
        ::new (static_cast<void*>(p)) U;
    }
    template <class U, class... A>
    void construct(U* p, A&&... a) {
        ::new (static_cast<void*>(p)) U(std::forward<A>(a)...);
    }
};

}  // namespace normalflow::detail
