// Rendering allocates nothing once the first frame has sized every buffer
// (the synthetic camera renders in the capture thread's per-frame path).
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "sim/renderer.h"
#include "tests/sim/sim_test_support.h"

namespace {

// Counts operator new calls made while `counting` is set on this thread.
thread_local bool counting = false;
std::atomic<int> allocations{0};

}  // namespace

void* operator new(std::size_t size) {
  if (counting) allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
// GCC cannot tell that these replace the global operator delete and flags
// free() of memory that came from operator new.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
#pragma GCC diagnostic pop

namespace ceilpose::sim {
namespace {

TEST(RendererAllocation, SecondFrameWithEveryNonJpegEffectAllocatesNothing) {
  // JPEG is left out: OpenCV's codec allocates internally.
  const Effects e = testing::every_effect(0);
  SceneOptions options;
  Renderer renderer(options);
  Image img;
  renderer.render({1.0, 1.0, 0.2}, CameraMount{}, e, 1, &img);
  // The hook sees allocations (not bypassed by the standard library).
  allocations = 0;
  counting = true;
  // Through a volatile pointer: a plain new/delete pair may be elided.
  void* (*volatile allocate)(std::size_t) = &::operator new;
  ::operator delete(allocate(16));
  counting = false;
  ASSERT_EQ(allocations.load(), 1);
  allocations = 0;
  counting = true;
  renderer.render({2.0, 1.5, 1.2}, CameraMount{}, e, 2, &img);
  counting = false;
  EXPECT_EQ(allocations.load(), 0);
}

}  // namespace
}  // namespace ceilpose::sim
