#pragma once
// The per-frame paths promise no allocation; tests prove it with this.
// Only C++'s operator new is counted: C libraries (Cyclone DDS, libc)
// allocate with malloc, which this cannot see.
// Counts the global operator new calls the current thread makes while
// counting is on (the replacement lives in alloc_count.cpp, a
// translation unit of its own so that it is never inlined into callers).
namespace ceilpose::test {

void start_counting_allocations();
// Stops counting and returns how many allocations were made since start.
long stop_counting_allocations();

}  // namespace ceilpose::test
