#pragma once
// Whole small files. Reading one a person wrote (configuration, ceiling map,
// camera calibration) accepts only a regular file and only up to a bound, so
// that a directory or /dev/zero given by mistake is an error, not an empty
// file or a read without end. Writing one reports every failure.
#include <cstddef>
#include <string>

#include "core/result.h"

namespace ceilpose {

// Errors name the file and say what it is meant to be (`what`, e.g.
// "configuration file") and why it cannot be read.
Result<std::string> read_text_file(const std::string& path, const char* what,
                                   size_t max_bytes = size_t{16} << 20);

// Creates or truncates `path` and writes all of `data`; errors (a full disk,
// a failing close, a symbolic link at `path`, which is not followed) name
// the file.
Result<void> write_file(const std::string& path, const void* data, size_t size);

// Writes `text` to a temporary file beside `path`, flushes it to disk and
// renames it over `path`: readers see the old file or the whole new one,
// never a half-written one (a map or calibration that a daemon reloads).
// `mode` is the new file's permission bits (0600 for a private key).
Result<void> replace_file(const std::string& path, const std::string& text, unsigned mode = 0644);

}  // namespace ceilpose
