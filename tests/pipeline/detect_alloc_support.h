#pragma once
// Counts the global operator new calls the current thread makes while
// counting is on (the replacement lives in detect_alloc_support.cpp, a
// translation unit of its own so that it is never inlined into callers).
namespace ceilpose::test {

void start_counting_allocations();
// Stops counting and returns how many allocations were made since start.
long stop_counting_allocations();

}  // namespace ceilpose::test
