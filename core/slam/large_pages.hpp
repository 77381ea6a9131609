#pragma once
// An allocator for large grids read at random (the global search's score levels): blocks of 2 MiB
// or more are aligned to 2 MiB and marked for transparent huge pages (madvise, Linux), so that a
// lookup anywhere in tens of megabytes needs few TLB entries, and the kernel maps the memory in a
// fault per 2 MiB rather than per 4 KiB (on some virtual machines a page fault costs 10 µs: a
// 20 MB grid took longer to fault in than to compute). Where huge pages are not available the
// advice is ignored and the memory is ordinary.
//
//   LargePageVector<uint8_t> grid(cells, 0);
#include <cstddef>
#include <cstdlib>
#include <memory>
#include <new>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace polarslam {

inline constexpr size_t kLargePageBytes = size_t{2} << 20;

template <typename T>
struct LargePageAllocator {
  using value_type = T;
  LargePageAllocator() = default;
  template <typename U>
  explicit LargePageAllocator(const LargePageAllocator<U>&) {}

  T* allocate(size_t n) {
    if (n > std::allocator_traits<std::allocator<T>>::max_size(std::allocator<T>())) throw std::bad_array_new_length();
    const size_t bytes = n * sizeof(T);
    if (bytes < kLargePageBytes) return std::allocator<T>().allocate(n);
    void* memory = std::aligned_alloc(kLargePageBytes, roundedUp(bytes));
    if (memory == nullptr) throw std::bad_alloc();
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    madvise(memory, roundedUp(bytes), MADV_HUGEPAGE);  // advice: failing leaves ordinary pages
#endif
    return static_cast<T*>(memory);
  }
  void deallocate(T* p, size_t n) {
    if (n * sizeof(T) < kLargePageBytes) std::allocator<T>().deallocate(p, n);
    else std::free(p);
  }
  template <typename U>
  bool operator==(const LargePageAllocator<U>&) const {
    return true;
  }

 private:
  static size_t roundedUp(size_t bytes) { return (bytes + kLargePageBytes - 1) / kLargePageBytes * kLargePageBytes; }
};

template <typename T>
using LargePageVector = std::vector<T, LargePageAllocator<T>>;

}  // namespace polarslam
