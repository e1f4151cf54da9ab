// Writes a configuration back as YAML by walking the same schema the loader
// reads, so `ceilposed --print-config` output loads back unchanged.
#include <charconv>
#include <sstream>

#include "config/config_schema.h"

namespace ceilpose {
namespace {

using config_detail::Choices;
using config_detail::TextCheck;

// A YAML double-quoted scalar. Control characters are escaped: written raw,
// a line break inside the quotes is folded to a space when read back (the
// config fuzzer found a calibration_file holding one).
std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (char ch : s) {
    const auto byte = static_cast<unsigned char>(ch);
    if (byte < 0x20 || byte == 0x7f) {
      static constexpr char kHex[] = "0123456789abcdef";
      out += "\\x";
      out += kHex[byte >> 4];
      out += kHex[byte & 15];
      continue;
    }
    if (ch == '"' || ch == '\\') out += '\\';
    out += ch;
  }
  return out + "\"";
}

// Shortest text that reads back as the same double, always with a '.' or an
// exponent so that YAML readers see a float.
template <typename T>
std::string double_text(T v) {
  char buf[64];
  auto [end, ec] = std::to_chars(buf, buf + sizeof(buf), v);
  std::string s(buf, ec == std::errc() ? end : buf);
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";
  return s;
}

// Writes YAML text to `out`, or (flat) collects "section.key" -> value pairs.
class Writer {
 public:
  explicit Writer(std::ostringstream* out) : out_(out) {}
  explicit Writer(std::vector<std::pair<std::string, std::string>>* flat) : flat_(flat) {}

  template <typename Fn>
  void section(const char* name, Fn fn) {
    if (out_ != nullptr) line(name, "");
    const std::string outer = prefix_;  // sections nest (dds.security.keystore)
    prefix_ += std::string(name) + ".";
    indent_ += 2;
    fn();
    indent_ -= 2;
    prefix_ = outer;
  }
  void field(const char* name, int& v, int, int) { line(name, std::to_string(v)); }
  void field(const char* name, uint64_t& v, uint64_t, uint64_t) { line(name, std::to_string(v)); }
  void field(const char* name, uint32_t& v, uint32_t, uint32_t) { line(name, std::to_string(v)); }
  void field(const char* name, double& v, double, double) { line(name, double_text(v)); }
  void field(const char* name, float& v, float, float) { line(name, double_text(v)); }
  void field(const char* name, bool& v) { line(name, v ? "true" : "false"); }
  void text(const char* name, std::string& v, TextCheck) { line(name, quoted(v)); }
  void texts(const char* name, std::vector<std::string>& v, TextCheck) {
    std::string s = "[";
    for (size_t i = 0; i < v.size(); ++i) {
      if (i > 0) s += ", ";
      s += quoted(v[i]);
    }
    line(name, s + "]");
  }
  template <typename T>
  void choice(const char* name, T& v, Choices<T> choices) {
    for (const auto& [text, value] : choices)
      if (value == v) return line(name, text);
  }
  template <size_t N>
  void numbers(const char* name, std::array<double, N>& v) {
    std::string s = "[";
    for (size_t i = 0; i < N; ++i) {
      if (i > 0) s += ", ";
      s += double_text(v[i]);
    }
    line(name, s + "]");
  }
  void colour(const char* name, Rgb& v) {
    std::string s = "[";
    s.append(std::to_string(v.r)).append(", ").append(std::to_string(v.g)).append(", ");
    s.append(std::to_string(v.b)).append("]");
    line(name, s);
  }

 private:
  void line(const char* name, const std::string& value) {
    if (flat_ != nullptr) {
      flat_->emplace_back(prefix_ + name, value);
      return;
    }
    *out_ << std::string(indent_, ' ') << name << ":" << (value.empty() ? "" : " ") << value
          << "\n";
  }
  std::ostringstream* out_ = nullptr;
  std::vector<std::pair<std::string, std::string>>* flat_ = nullptr;
  std::string prefix_;
  int indent_ = 0;
};

// Collects key paths only.
class KeyLister {
 public:
  template <typename Fn>
  void section(const char* name, Fn fn) {
    const std::string outer = prefix_;
    prefix_ += std::string(name) + ".";
    fn();
    prefix_ = outer;
  }
  template <typename... A>
  void field(const char* name, A&&...) {
    add(name);
  }
  template <typename... A>
  void text(const char* name, A&&...) {
    add(name);
  }
  template <typename... A>
  void texts(const char* name, A&&...) {
    add(name);
  }
  template <typename T>
  void choice(const char* name, T&, Choices<T>) {
    add(name);
  }
  template <typename... A>
  void numbers(const char* name, A&&...) {
    add(name);
  }
  template <typename... A>
  void colour(const char* name, A&&...) {
    add(name);
  }
  std::vector<std::string> keys;

 private:
  void add(const char* name) { keys.push_back(prefix_ + name); }
  std::string prefix_;
};

}  // namespace

std::string dump_config(const ServiceConfig& config) {
  ServiceConfig copy = config;  // the schema walks mutable references
  std::ostringstream out;
  Writer writer(&out);
  config_detail::describe(writer, copy);
  return out.str();
}

std::vector<std::pair<std::string, std::string>> config_values(const ServiceConfig& config) {
  ServiceConfig copy = config;
  std::vector<std::pair<std::string, std::string>> values;
  Writer writer(&values);
  config_detail::describe(writer, copy);
  return values;
}

bool is_live_key(std::string_view key) {
  for (const char* restart : config_detail::kRestartKeys)
    if (key == restart) return false;
  for (const char* section : config_detail::kLiveSections) {
    const std::string_view name(section);
    if (key.size() > name.size() && key.substr(0, name.size()) == name && key[name.size()] == '.')
      return true;
  }
  return false;
}

namespace {
template <size_t N>
std::string listed(const std::array<const char*, N>& names) {
  std::string text;
  for (size_t i = 0; i < N; ++i)
    text += std::string(i == 0 ? "" : i + 1 == N ? " and " : ", ") + names[i];
  return text;
}
}  // namespace

std::string live_keys_phrase() {
  return "the " + listed(config_detail::kLiveSections) + " keys live, but not " +
         listed(config_detail::kRestartKeys);
}

ServiceConfig with_live_keys(const ServiceConfig& running, const ServiceConfig& next) {
  // Whole structs, then the restart keys put back: the loaded map and
  // camera files travel with pipeline and calibration.
  ServiceConfig live = running;
  live.pipeline = next.pipeline;
  live.calibration = next.calibration;
  live.pipeline.intrinsics.width = running.pipeline.intrinsics.width;
  live.pipeline.intrinsics.height = running.pipeline.intrinsics.height;
  live.logging = next.logging;
  return live;
}

std::vector<std::string> changed_config_keys(const ServiceConfig& a, const ServiceConfig& b) {
  const auto va = config_values(a);
  const auto vb = config_values(b);
  std::vector<std::string> changed;
  for (size_t i = 0; i < va.size(); ++i)
    if (va[i].second != vb[i].second) changed.push_back(va[i].first);
  // The same map file may hold another survey now: compare what was read.
  const CeilingMap* ma = a.pipeline.map.get();
  const CeilingMap* mb = b.pipeline.map.get();
  const bool map_differs = (ma == nullptr) != (mb == nullptr) || (ma != nullptr && !(*ma == *mb));
  if (map_differs && a.calibration.map_file == b.calibration.map_file)
    changed.push_back("ceiling.map");
  return changed;
}

std::vector<std::string> config_key_paths() {
  ServiceConfig scratch;
  KeyLister lister;
  config_detail::describe(lister, scratch);
  return lister.keys;
}

}  // namespace ceilpose
