#pragma once
// The ceiling map file of SPEC §8: a strict reader and a writer.
#include <string>

#include "core/ceiling_layout.h"
#include "core/ceiling_map.h"
#include "core/result.h"

namespace ceilpose {

inline constexpr const char* kMapFormat = "ceilpose-map";
inline constexpr int kMapVersion = 1;

// Reads a map for a ceiling of `layout`. Rejects, naming the file, the line
// and the entry: malformed YAML, a wrong format or version, a ceiling block
// whose grid, height or bits differ from `layout`'s, a code listed twice or
// outside `bits`, a non-finite number, a negative sigma, an unknown key.
Result<CeilingMap> read_map_file(const std::string& path, const CeilingLayout& layout);

// The map as SPEC §8 text: every present marker, codes in (j, i) order,
// centres to 1 µm, angles to 0.1 µrad.
std::string map_text(const CeilingMap& map, const CeilingLayout& layout);

// Writes map_text() so that a reader never sees a half-written file.
Result<void> write_map_file(const std::string& path, const CeilingMap& map,
                            const CeilingLayout& layout);

}  // namespace ceilpose
