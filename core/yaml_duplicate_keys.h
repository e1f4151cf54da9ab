#pragma once
// yaml-cpp keeps both entries of a key written twice and a lookup answers the
// first: a file a person edited could then mean something else than what it
// shows. Readers of such files (recording.yaml, calibration, the ceiling
// map, the configuration) refuse it and aliases with these. Header-only:
// core itself does not link yaml-cpp.
#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include <set>
#include <sstream>
#include <string>

#include "core/result.h"

namespace ceilpose {

// One pass of yaml-cpp's event parser over the text before it is loaded,
// refusing what would make loading it cost more than its size says:
// - aliases (*name): nothing ceilpose reads needs them, and each alias of an
//   alias multiplies what a walk over the tree visits (issue 28: a 10 kB
//   "billion laughs" map took 52 s, in the daemon's control thread on a
//   reload);
// - more than `max_nodes` nodes (scalars, lists, mappings): a tree costs
//   ~70 bytes of memory per byte of text (issue 28: an 11 MB map needed
//   780 MB, and a reload under a memory limit killed the daemon), so each
//   reader bounds its file by the entries it can hold, not only its bytes.
// A syntax error is left for the loader to report, with its line.
inline Result<void> check_plain_yaml(const std::string& text, const std::string& path,
                                     size_t max_nodes) {
  struct TooManyNodes {
    YAML::Mark mark;
  };
  class Finder final : public YAML::EventHandler {
   public:
    explicit Finder(size_t max_nodes) : max_nodes_(max_nodes) {}
    void OnDocumentStart(const YAML::Mark&) override {}
    void OnDocumentEnd() override {}
    void OnNull(const YAML::Mark& mark, YAML::anchor_t) override { count(mark); }
    void OnAlias(const YAML::Mark& mark, YAML::anchor_t) override {
      if (line < 0) line = mark.line;
    }
    void OnScalar(const YAML::Mark& mark, const std::string&, YAML::anchor_t,
                  const std::string&) override {
      count(mark);
    }
    void OnSequenceStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t,
                         YAML::EmitterStyle::value) override {
      count(mark);
    }
    void OnSequenceEnd() override {}
    void OnMapStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t,
                    YAML::EmitterStyle::value) override {
      count(mark);
    }
    void OnMapEnd() override {}
    int line = -1;

   private:
    void count(const YAML::Mark& mark) {
      if (++nodes_ > max_nodes_) throw TooManyNodes{mark};
    }
    size_t max_nodes_;
    size_t nodes_ = 0;
  } finder(max_nodes);
  try {
    // The first document only, as YAML::Load reads; looping over documents
    // never ended on some inputs (found by fuzz_map and its siblings).
    std::istringstream in(text);
    YAML::Parser parser(in);
    parser.HandleNextDocument(finder);
  } catch (const TooManyNodes& e) {
    return make_error(path + ":" + std::to_string(e.mark.line + 1) + ": more than " +
                      std::to_string(max_nodes) +
                      " YAML entries (values, lists, mappings), more than a file of this kind "
                      "can hold; is it the right file?");
  } catch (const YAML::Exception&) {
    return {};  // the loader reports it, with its line
  }
  if (finder.line < 0) return {};
  return make_error(path + ":" + std::to_string(finder.line + 1) +
                    ": YAML aliases (*name) are not accepted; write the value out");
}

// The first key that appears twice in one mapping anywhere in `node`, as
// "PATH:LINE: key 'a.b' appears twice"; success when there is none.
inline Result<void> check_no_duplicate_keys(const YAML::Node& node, const std::string& path,
                                            const std::string& key_path = "") {
  if (node.IsSequence()) {
    for (size_t i = 0; i < node.size(); ++i) {
      auto ok = check_no_duplicate_keys(node[i], path, key_path + "[" + std::to_string(i) + "]");
      if (!ok) return ok;
    }
  }
  if (!node.IsMap()) return {};
  std::set<std::string> seen;
  for (const auto& entry : node) {
    const std::string key = entry.first.IsScalar() ? entry.first.Scalar() : std::string("?");
    const std::string full = key_path.empty() ? key : key_path + "." + key;
    if (!seen.insert(key).second) {
      return make_error(path + ":" + std::to_string(entry.first.Mark().line + 1) + ": key '" +
                        full + "' appears twice");
    }
    if (auto ok = check_no_duplicate_keys(entry.second, path, full); !ok) return ok;
  }
  return {};
}

}  // namespace ceilpose
