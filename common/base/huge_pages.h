// Transparent huge pages for the large arrays of a build: without them a third of a flat build was
// the kernel's first-touch faults of 4 KB pages (perf, salledebain).  Debian's kernels default to
// THP "madvise", so memory is backed by 2 MB pages only where a program asks; Embree asks for its
// own arrays, and we do the same for ours.
#pragma once

#include <cstddef>
#include <vector>

namespace ls {

// Asks the kernel to back the whole 2 MB pages inside [p, p + bytes) with huge pages.  A hint: does
// nothing for small ranges, where THP is off or unsupported, or when the kernel refuses.
void advise_huge_pages(void* p, size_t bytes);

// v.reserve(n), with the new storage advised before anything touches it.
template <class T, class A>
void reserve_huge(std::vector<T, A>& v, size_t n) {
  v.reserve(n);
  advise_huge_pages(v.data(), v.capacity() * sizeof(T));
}

// v.resize(n) (value-initialised), with the storage advised before it is written.
template <class T, class A>
void resize_huge(std::vector<T, A>& v, size_t n) {
  if (n > v.capacity()) reserve_huge(v, n);
  v.resize(n);
}

}  // namespace ls
