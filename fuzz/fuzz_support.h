#pragma once
// What the fuzz targets share: a scratch directory in /dev/shm (files are
// what the readers read), one per process, emptied for every input.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace ceilpose::fuzz {

// A fresh, empty directory for this input; the same path every time.
const std::string& scratch_dir();
void write_bytes(const std::string& path, std::string_view bytes);

// An invariant of what a reader accepted does not hold: says which and
// aborts, so that libFuzzer keeps the input as a crash.
[[noreturn]] void invariant_broken(const char* target, const std::string& what);

// Splits `data` at the first `count - 1` separator lines "\n--8<--\n" into
// `count` parts (missing ones are empty): one input becomes several files.
void split_input(const uint8_t* data, size_t size, std::string_view* parts, int count);

}  // namespace ceilpose::fuzz
