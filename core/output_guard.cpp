#include "core/output_guard.h"

#include <filesystem>
#include <system_error>

namespace ceilpose {
namespace {

namespace fs = std::filesystem;

// Both paths reach the same file: the same inode when both exist, else the
// same absolute, normalised spelling (an output not yet written may still be
// the same path as another output).
bool same_file(const std::string& a, const std::string& b) {
  std::error_code ec;
  if (fs::equivalent(a, b, ec) && !ec) return true;
  const fs::path na = fs::absolute(a, ec).lexically_normal();
  const fs::path nb = fs::absolute(b, ec).lexically_normal();
  return !ec && na == nb;
}

// `file` lies inside directory `dir` (resolved through symbolic links as far
// as they exist).
bool inside(const std::string& file, const std::string& dir) {
  std::error_code ec;
  const fs::path d = fs::weakly_canonical(dir, ec);
  if (ec) return false;
  const fs::path f = fs::weakly_canonical(file, ec);
  if (ec) return false;
  const fs::path rel = f.lexically_relative(d);
  return !rel.empty() && *rel.begin() != "..";
}

}  // namespace

Result<void> check_outputs_are_not_inputs(const std::vector<NamedPath>& outputs,
                                          const std::vector<NamedPath>& input_files,
                                          const std::vector<NamedPath>& input_dirs) {
  for (size_t o = 0; o < outputs.size(); ++o) {
    const NamedPath& out = outputs[o];
    if (out.path.empty()) continue;
    for (const NamedPath& in : input_files)
      if (!in.path.empty() && same_file(out.path, in.path))
        return make_error(out.option + " " + out.path + " is " + in.option +
                          "'s file: writing it would replace an input; choose another path");
    for (const NamedPath& in : input_dirs)
      if (!in.path.empty() && inside(out.path, in.path))
        return make_error(out.option + " " + out.path + " is inside " + in.option + " " + in.path +
                          ": writing it would change an input; choose another path");
    for (size_t p = 0; p < o; ++p)
      if (!outputs[p].path.empty() && same_file(out.path, outputs[p].path))
        return make_error(out.option + " and " + outputs[p].option + " are both " + out.path +
                          ": one would overwrite the other; choose two paths");
  }
  return {};
}

}  // namespace ceilpose
