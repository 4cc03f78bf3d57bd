// The counting operator new/delete (platform/memory/counting_operator_new.h) that the allocation
// tests and `voca bench soak` rely on: every form of operator new is counted, and what each returns
// is released by the matching delete. Under ASan a form left unreplaced allocates from the
// sanitizer's own operator new, which the replaced delete then frees with std::free: an
// alloc-dealloc mismatch, reported as an error.

#include <doctest/doctest.h>

#include <algorithm>
#include <cstdint>
#include <new>
#include <string>
#include <vector>

#include "tests/test_alloc_counter.h"

namespace {

long callsDuring(auto&& work) {
  const long before = voca::test::g_allocations.load();
  work();
  return voca::test::g_allocations.load() - before;
}

struct alignas(64) CacheLine {
  unsigned char bytes[64];
};

// New-expressions whose result is only deleted may be elided by the compiler; storing the pointer
// here keeps them real.
CacheLine* volatile g_escape = nullptr;
template <typename T>
T* escape(T* p) {
  g_escape = p;
  return p;
}

}  // namespace

TEST_CASE("counting operator new: installed, and every form counts once") {
  CHECK(voca::platform::operatorNewCounted());
  CHECK(callsDuring([] { ::operator delete(::operator new(24)); }) == 1);
  CHECK(callsDuring([] { ::operator delete[](::operator new[](24)); }) == 1);
  CHECK(callsDuring([] { ::operator delete(::operator new(24, std::nothrow), std::nothrow); }) == 1);
  CHECK(callsDuring([] { ::operator delete[](::operator new[](24, std::nothrow), std::nothrow); }) == 1);
  CHECK(callsDuring([] { delete escape(new CacheLine); }) == 1);
  CHECK(callsDuring([] { delete[] escape(new CacheLine[3]); }) == 1);
  CHECK(callsDuring([] { delete escape(new (std::nothrow) CacheLine); }) == 1);
  CHECK(callsDuring([] { delete[] escape(new (std::nothrow) CacheLine[3]); }) == 1);
  CHECK(callsDuring([] { ::operator delete(::operator new(0)); }) == 1);  // size 0 still gets a pointer
  CacheLine* aligned = escape(new CacheLine);
  CHECK(reinterpret_cast<std::uintptr_t>(aligned) % alignof(CacheLine) == 0);
  delete aligned;
}

TEST_CASE("counting operator new: std::stable_sort's buffer (nothrow new) is counted and freed") {
  std::vector<std::string> words;
  for (int i = 0; i < 500; ++i) words.push_back("word " + std::to_string((i * 7919) % 500));
  const long calls = callsDuring([&] {
    std::stable_sort(words.begin(), words.end(),
                     [](const std::string& a, const std::string& b) { return a.size() < b.size(); });
  });
  CHECK(calls >= 1);
  CHECK(std::is_sorted(words.begin(), words.end(),
                       [](const std::string& a, const std::string& b) { return a.size() < b.size(); }));
}
