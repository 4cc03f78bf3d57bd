#pragma once
// Counting replacements of the global operator new/delete (allocation_count.h reads the count): for
// tests that prove a hot path does not allocate, and for `voca bench soak`, which measures it over
// hours. Include in exactly one source file of an executable: they replace the program's operators.

#include <cstdlib>
#include <new>

#include "platform/memory/allocation_count.h"

namespace voca::platform {
inline const bool kOperatorNewCountingInstalled = (g_operator_new_counted.store(true), true);
}  // namespace voca::platform

// Exported: the project builds with hidden visibility, and shared libraries loaded later must call
// these too.
#pragma GCC visibility push(default)
// Every form counts once and allocates in one of the two nothrow forms; the nothrow forms are replaced
// too (std::stable_sort's buffer uses one), since a runtime that provides its own, like a sanitizer's,
// would otherwise allocate what the replaced delete below frees with std::free.
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  voca::platform::g_operator_new_calls.fetch_add(1, std::memory_order_relaxed);
  return std::malloc(size == 0 ? 1 : size);
}
void* operator new(std::size_t size, std::align_val_t align, const std::nothrow_t&) noexcept {
  voca::platform::g_operator_new_calls.fetch_add(1, std::memory_order_relaxed);
  const std::size_t a = static_cast<std::size_t>(align);
  return std::aligned_alloc(a, (size + a - 1) / a * a);
}
void* operator new(std::size_t size) {
  if (void* p = operator new(size, std::nothrow)) return p;
  throw std::bad_alloc();
}
void* operator new(std::size_t size, std::align_val_t align) {
  if (void* p = operator new(size, align, std::nothrow)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) { return operator new(size); }
void* operator new[](std::size_t size, std::align_val_t align) { return operator new(size, align); }
void* operator new[](std::size_t size, const std::nothrow_t& tag) noexcept { return operator new(size, tag); }
void* operator new[](std::size_t size, std::align_val_t align, const std::nothrow_t& tag) noexcept {
  return operator new(size, align, tag);
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
#pragma GCC visibility pop
