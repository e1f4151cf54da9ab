#include "recording/recording_reader.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <new>
#include <sstream>
#include <string_view>

#include "codec/jpeg_codec.h"
#include "codec/png_codec.h"
#include "core/message_text.h"
#include "core/text_file.h"
#include "core/yaml_duplicate_keys.h"
#include "recording/frame_file.h"
#include "recording/recording_format.h"

namespace ceilpose {

namespace fmt = recording_format;

struct RecordingReader::DecodeBuffers {
  std::vector<uint8_t> file_bytes;  // the encoded frame, reused across frames
  FrameFileInfo info;
  codec::JpegCodec jpeg;  // the decoder's handle, reused
};

std::unique_ptr<RecordingReader::DecodeBuffers, RecordingReader::DecodeBuffersDeleter>
RecordingReader::make_decode_buffers() {
  return std::unique_ptr<DecodeBuffers, DecodeBuffersDeleter>(new DecodeBuffers());
}

void RecordingReader::DecodeBuffersDeleter::operator()(DecodeBuffers* b) const { delete b; }

namespace {

// 'text' for an error message: escaped, and cut when long (core/message_text.h).
std::string quoted(std::string_view text) { return shown_value(text); }

// ---- recording.yaml -------------------------------------------------------

int line_of(const YAML::Node& node) { return node.Mark().line + 1; }

// Keys under `camera` are named "camera.<key>" in messages.
std::string key_name(const char* parent_key, const char* key) {
  return std::string(parent_key) + (*parent_key != '\0' ? "." : "") + key;
}

template <typename T>
Result<T> yaml_scalar(const YAML::Node& parent, const char* parent_key, const char* key,
                      const std::string& where, const char* expected) {
  const YAML::Node node = parent[key];
  if (!node.IsDefined() || node.IsNull()) {
    return make_error(where + ":" + std::to_string(line_of(parent)) + ": missing key '" +
                      key_name(parent_key, key) + "'");
  }
  T value{};
  if (!node.IsScalar() || !YAML::convert<T>::decode(node, value)) {
    return make_error(where + ":" + std::to_string(line_of(node)) + ": key '" +
                      key_name(parent_key, key) + "' must be " + expected);
  }
  return value;
}

Result<double> yaml_camera_number(const YAML::Node& camera, const char* key,
                                  const std::string& where, bool positive) {
  const char* expected = positive ? "a positive number" : "a finite number";
  auto v = yaml_scalar<double>(camera, "camera", key, where, expected);
  if (!v) return v;
  if (!std::isfinite(*v) || (positive && *v <= 0.0)) {
    return make_error(where + ":" + std::to_string(line_of(camera[key])) + ": key 'camera." + key +
                      "' must be " + expected);
  }
  return v;
}

Result<RecordingCamera> parse_yaml(const std::string& path) {
  YAML::Node root;
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0 && errno == ENOENT)
    return make_error(path + ": missing (not a recording directory?)");
  // A regular file of a sane size: not a directory, a FIFO or /dev/zero.
  auto text = read_text_file(path, "recording.yaml", size_t{1} << 20);
  if (!text) return text.error();
  constexpr size_t kMaxRecordingYamlNodes = 10000;  // SPEC §4 needs a few dozen
  if (auto plain = check_plain_yaml(*text, path, kMaxRecordingYamlNodes); !plain)
    return plain.error();
  try {
    root = YAML::Load(*text);
  } catch (const YAML::ParserException& e) {
    return make_error(path + ":" + std::to_string(e.mark.line + 1) + ":" +
                      std::to_string(e.mark.column + 1) + ": YAML syntax error: " + e.msg);
  } catch (const YAML::Exception& e) {
    return make_error(path + ": YAML error: " + e.what());
  }
  if (!root.IsMap()) {
    return make_error(path + ":1: expected a mapping with keys format, version, camera");
  }
  if (auto unique = check_no_duplicate_keys(root, path); !unique) return unique.error();
  auto format = yaml_scalar<std::string>(root, "", "format", path, "a string");
  if (!format) return format.error();
  if (*format != fmt::kFormat) {
    return make_error(path + ":" + std::to_string(line_of(root["format"])) + ": format " +
                      quoted(*format) + " is not '" + fmt::kFormat + "'");
  }
  auto version = yaml_scalar<int>(root, "", "version", path, "an integer");
  if (!version) return version.error();
  if (*version != fmt::kVersion) {
    return make_error(path + ":" + std::to_string(line_of(root["version"])) +
                      ": unsupported version " + std::to_string(*version) +
                      " (this reader knows version " + std::to_string(fmt::kVersion) + ")");
  }
  const YAML::Node cam = root["camera"];
  if (!cam.IsDefined() || cam.IsNull()) {
    return make_error(path + ":" + std::to_string(line_of(root)) + ": missing key 'camera'");
  }
  if (!cam.IsMap()) {
    return make_error(path + ":" + std::to_string(line_of(cam)) +
                      ": key 'camera' must be a mapping (width, height, fx, fy, cx, cy, "
                      "distortion)");
  }
  RecordingCamera out;
  CameraIntrinsics& k = out.intrinsics;
  namespace ck = camera_keys;
  for (auto [key, dst] : {std::pair{ck::kWidth, &k.width}, std::pair{ck::kHeight, &k.height}}) {
    auto v = yaml_scalar<int>(cam, "camera", key, path, "a positive integer");
    if (!v) return v.error();
    if (*v <= 0 || *v > kMaxImageSidePx) {
      return make_error(path + ":" + std::to_string(line_of(cam[key])) + ": key 'camera." + key +
                        "' must be 1 to " + std::to_string(kMaxImageSidePx) + " pixels, got " +
                        std::to_string(*v));
    }
    *dst = *v;
  }
  if (static_cast<long>(k.width) * k.height > kMaxImagePixels) {
    return make_error(path + ":" + std::to_string(line_of(cam[ck::kHeight])) +
                      ": camera.width x camera.height must be at most " +
                      std::to_string(kMaxImagePixels) + " pixels, got " + std::to_string(k.width) +
                      "x" + std::to_string(k.height));
  }
  for (auto [key, dst, positive] :
       {std::tuple{ck::kFx, &k.fx, true}, std::tuple{ck::kFy, &k.fy, true},
        std::tuple{ck::kCx, &k.cx, false}, std::tuple{ck::kCy, &k.cy, false}}) {
    auto v = yaml_camera_number(cam, key, path, positive);
    if (!v) return v.error();
    *dst = *v;
  }
  // distortion is optional (absent means none), but when present it is
  // exactly the five plumb_bob coefficients.
  const YAML::Node dist = cam[ck::kDistortion];
  if (dist.IsDefined() && !dist.IsNull()) {
    if (!dist.IsSequence() || dist.size() != fmt::kDistortionCoefficients) {
      return make_error(
          path + ":" + std::to_string(line_of(dist)) +
          ": key 'camera.distortion' must be a list of 5 numbers [k1, k2, p1, p2, k3]");
    }
    for (int c = 0; c < fmt::kDistortionCoefficients; ++c) {
      double v = 0.0;
      if (!dist[c].IsScalar() || !YAML::convert<double>::decode(dist[c], v) || !std::isfinite(v)) {
        return make_error(path + ":" + std::to_string(line_of(dist[c])) + ": camera.distortion[" +
                          std::to_string(c) + "] must be a finite number");
      }
      k.distortion[static_cast<size_t>(c)] = v;
    }
    if (const std::string lens = distortion_problem(k); !lens.empty())
      return make_error(path + ":" + std::to_string(line_of(dist)) +
                        ": camera.distortion: " + lens);
  }
  // readout_ms is optional (SPEC §3: absent means a global shutter).
  if (const YAML::Node readout = cam[ck::kReadoutMs]; readout.IsDefined() && !readout.IsNull()) {
    auto v = yaml_scalar<double>(cam, "camera", ck::kReadoutMs, path, "a number of milliseconds");
    if (!v) return v.error();
    if (!std::isfinite(*v) || *v < 0.0 || *v > kMaxReadoutMs) {
      return make_error(path + ":" + std::to_string(line_of(readout)) + ": key 'camera." +
                        ck::kReadoutMs + "' must be 0 to " +
                        std::to_string(static_cast<int>(kMaxReadoutMs)) + " ms");
    }
    k.readout_ms = *v;
  }
  const YAML::Node source = root["source"];
  if (source.IsDefined() && !source.IsNull()) {
    if (!source.IsScalar()) {
      return make_error(path + ":" + std::to_string(line_of(source)) +
                        ": key 'source' must be a string");
    }
    out.source = source.Scalar();
  }
  return out;
}

// ---- frames.csv -----------------------------------------------------------

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r'))
    s.remove_suffix(1);
  return s;
}

// Splits one CSV line (RFC 4180 quoting, no embedded newlines). Returns false
// on an unterminated quote.
bool split_csv(std::string_view line, std::vector<std::string>* fields) {
  fields->clear();
  std::string cur;
  bool quoted = false;
  bool was_quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"') {
        if (i + 1 < line.size() && line[i + 1] == '"') {
          cur += '"';
          ++i;
        } else {
          quoted = false;
        }
      } else {
        cur += c;
      }
    } else if (c == '"' && trim(cur).empty()) {
      cur.clear();
      quoted = true;
      was_quoted = true;
    } else if (c == ',') {
      fields->push_back(was_quoted ? cur : std::string(trim(cur)));
      cur.clear();
      was_quoted = false;
    } else {
      cur += c;
    }
  }
  if (quoted) return false;
  fields->push_back(was_quoted ? cur : std::string(trim(cur)));
  return true;
}

bool parse_int64(std::string_view s, int64_t* out) {
  if (s.empty()) return false;
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), *out);
  return ec == std::errc{} && p == s.data() + s.size();
}

bool parse_double(std::string_view s, double* out) {
  if (s.empty()) return false;
  if (s.front() == '+') s.remove_prefix(1);
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), *out);
  return ec == std::errc{} && p == s.data() + s.size() && std::isfinite(*out);
}

struct Columns {
  int index = -1, timestamp = -1, file = -1, gt_x = -1, gt_y = -1, gt_yaw = -1;
  size_t count = 0;
};

Result<Columns> parse_header(const std::vector<std::string>& names, const std::string& where) {
  Columns c;
  c.count = names.size();
  const std::pair<const char*, int*> known[] = {
      {fmt::kColIndex, &c.index}, {fmt::kColTimestamp, &c.timestamp},
      {fmt::kColFile, &c.file},   {fmt::kColGtX, &c.gt_x},
      {fmt::kColGtY, &c.gt_y},    {fmt::kColGtYaw, &c.gt_yaw}};
  for (size_t i = 0; i < names.size(); ++i) {
    for (const auto& [name, slot] : known) {
      if (names[i] != name) continue;
      if (*slot >= 0) {
        return make_error(where + ":1: column '" + name + "' appears twice in the header");
      }
      *slot = static_cast<int>(i);
    }
  }
  for (const auto& [name, slot] : {known[0], known[1], known[2]}) {
    if (*slot < 0) {
      return make_error(where + ":1: header lacks the required column '" + name + "' (need " +
                        fmt::kColIndex + "," + fmt::kColTimestamp + "," + fmt::kColFile + ")");
    }
  }
  const int gt = (c.gt_x >= 0) + (c.gt_y >= 0) + (c.gt_yaw >= 0);
  if (gt != 0 && gt != 3) {
    return make_error(where + ":1: ground truth needs all three columns " + fmt::kColGtX + ", " +
                      fmt::kColGtY + ", " + fmt::kColGtYaw);
  }
  return c;
}

Result<std::string> read_text(const std::string& path, const char* what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0 && errno == ENOENT) return make_error(path + ": missing");
    return make_error(path + ": cannot be read (" + what + ")");
  }
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) return make_error(path + ": read error");
  return ss.str();
}

// One data row of frames.csv, checked against the row before it (`previous`,
// null for the first): index in sequence, timestamp not going backwards, a
// relative file name, ground truth all three or none.
Result<RecordingRow> parse_row(const std::vector<std::string>& fields, const Columns& cols,
                               bool ground_truth_columns, const RecordingRow* previous,
                               int64_t expected_index, int line_no, const std::string& where) {
  if (fields.size() != cols.count) {
    return make_error(where + ": " + std::to_string(fields.size()) + " fields, the header has " +
                      std::to_string(cols.count));
  }
  RecordingRow row;
  row.csv_line = line_no;
  if (!parse_int64(fields[cols.index], &row.index)) {
    return make_error(where + ": index " + quoted(fields[cols.index]) + " is not an integer");
  }
  if (row.index != expected_index) {
    return make_error(where + ": index " + std::to_string(row.index) +
                      " out of sequence (expected " + std::to_string(expected_index) +
                      "; indices count from 0 without gaps)");
  }
  if (!parse_int64(fields[cols.timestamp], &row.timestamp_ns)) {
    return make_error(where + ": timestamp_ns " + quoted(fields[cols.timestamp]) +
                      " is not an integer");
  }
  if (previous != nullptr && row.timestamp_ns < previous->timestamp_ns) {
    return make_error(where + ": timestamp_ns " + std::to_string(row.timestamp_ns) +
                      " goes backwards (previous " + std::to_string(previous->timestamp_ns) + ")");
  }
  row.file = fields[cols.file];
  if (row.file.empty()) return make_error(where + ": empty file name");
  if (row.file.front() == '/') {
    return make_error(where + ": file " + quoted(row.file) +
                      " must be relative to the recording directory");
  }
  // Nor may it climb out of it.
  for (size_t start = 0; start <= row.file.size();) {
    const size_t end = std::min(row.file.find('/', start), row.file.size());
    if (row.file.compare(start, end - start, "..") == 0) {
      return make_error(where + ": file " + quoted(row.file) +
                        " must stay inside the recording directory (no '..')");
    }
    start = end + 1;
  }
  if (!ground_truth_columns) return row;
  const std::string& gx = fields[cols.gt_x];
  const std::string& gy = fields[cols.gt_y];
  const std::string& gyaw = fields[cols.gt_yaw];
  // All three empty: this frame has no ground truth (e.g. a tracker lost it).
  if (gx.empty() && gy.empty() && gyaw.empty()) return row;
  for (auto [name, text, dst] : {std::tuple{"gt_x_m", &gx, &row.ground_truth.x_m},
                                 std::tuple{"gt_y_m", &gy, &row.ground_truth.y_m},
                                 std::tuple{"gt_yaw_rad", &gyaw, &row.ground_truth.yaw_rad}}) {
    if (!parse_double(*text, dst)) {
      return make_error(where + ": " + name + " " + quoted(*text) + " is not a finite number");
    }
  }
  row.has_ground_truth = true;
  return row;
}

// The frame file a row names must exist and be a regular file (a FIFO or a
// directory would hang or fail the decoder later).
Result<void> check_frame_file(const std::string& frame_path, int line_no) {
  struct stat fst {};
  if (::stat(frame_path.c_str(), &fst) != 0) {
    return make_error(shown_value(frame_path) + " (frames.csv:" + std::to_string(line_no) +
                      "): frame file missing (" + std::strerror(errno) + ")");
  }
  if (!S_ISREG(fst.st_mode)) {
    return make_error(shown_value(frame_path) + " (frames.csv:" + std::to_string(line_no) +
                      "): not a regular file");
  }
  return {};
}

}  // namespace

RecordingReader::RecordingReader() : scratch_(make_decode_buffers()) {}
RecordingReader::RecordingReader(RecordingReader&&) noexcept = default;
RecordingReader& RecordingReader::operator=(RecordingReader&&) noexcept = default;
RecordingReader::~RecordingReader() = default;

Result<RecordingReader> RecordingReader::open(const std::string& dir) {
  struct stat st {};
  if (::stat(dir.c_str(), &st) != 0) {
    return make_error(dir + ": recording directory does not exist (" + std::strerror(errno) + ")");
  }
  if (!S_ISDIR(st.st_mode)) return make_error(dir + ": not a directory");

  RecordingReader r;
  r.dir_ = dir;
  while (r.dir_.size() > 1 && r.dir_.back() == '/') r.dir_.pop_back();
  auto camera = parse_yaml(r.dir_ + "/" + fmt::kYamlName);
  if (!camera) return camera.error();
  r.camera_ = std::move(*camera);

  const std::string csv_path = r.dir_ + "/" + fmt::kCsvName;
  auto text = read_text(csv_path, "frames.csv");
  if (!text) return text.error();
  std::string_view all(*text);
  // Spreadsheet programs start CSV files with a UTF-8 byte-order mark.
  if (all.starts_with("\xEF\xBB\xBF")) all.remove_prefix(3);

  std::vector<std::string> fields;
  Columns cols;
  bool header_seen = false;
  int line_no = 0;
  int blank_line = 0;  // first blank line since the last row; only allowed at the end
  size_t pos = 0;
  while (pos < all.size()) {
    size_t eol = all.find('\n', pos);
    if (eol == std::string_view::npos) eol = all.size();
    const std::string_view line = trim(all.substr(pos, eol - pos));
    pos = eol + 1;
    ++line_no;
    const std::string where = csv_path + ":" + std::to_string(line_no);
    if (line.empty()) {
      if (blank_line == 0) blank_line = line_no;
      continue;
    }
    // A NUL would silently end the field it is in (a file name, a number).
    if (const size_t nul = line.find('\0'); nul != std::string_view::npos) {
      return make_error(where + ": a NUL byte at character " + std::to_string(nul + 1) +
                        " (binary data in a text file)");
    }
    if (blank_line != 0) {
      return make_error(csv_path + ":" + std::to_string(blank_line) +
                        ": empty line before the end of the file");
    }
    if (!split_csv(line, &fields)) return make_error(where + ": unterminated quoted field");
    if (!header_seen) {
      auto c = parse_header(fields, csv_path);
      if (!c) return c.error();
      cols = *c;
      header_seen = true;
      r.has_ground_truth_columns_ = cols.gt_x >= 0;
      continue;
    }
    auto row = parse_row(fields, cols, r.has_ground_truth_columns_,
                         r.rows_.empty() ? nullptr : &r.rows_.back(),
                         static_cast<int64_t>(r.rows_.size()), line_no, where);
    if (!row) return row.error();
    const std::string frame_path = r.dir_ + "/" + row->file;
    if (auto ok = check_frame_file(frame_path, line_no); !ok) return ok.error();
    r.rows_.push_back(std::move(row).value());
    r.frame_paths_.push_back(frame_path);
  }
  if (!header_seen) return make_error(csv_path + ":1: empty file, expected the header line");
  // One answer for every command (inspect, locate, evaluate, replay): a
  // recording without a frame is not one (docs/decisions.md).
  if (r.rows_.empty())
    return make_error(csv_path + ":" + std::to_string(line_no) +
                      ": no frames, only the header (a recording holds at least one frame)");
  return r;
}

std::string RecordingReader::frame_context(size_t i) const {
  if (i >= rows_.size()) return dir_ + ": frame " + std::to_string(i);
  return dir_ + "/" + rows_[i].file + " (frames.csv:" + std::to_string(rows_[i].csv_line) + ")";
}

Result<void> RecordingReader::read_frame_file(size_t i, DecodeBuffers* buffers) const {
  if (i >= rows_.size()) {
    return make_error(dir_ + ": frame " + std::to_string(i) + " out of range (recording has " +
                      std::to_string(rows_.size()) + " frames)");
  }
  const int fd = ::open(frame_paths_[i].c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    return make_error(frame_context(i) + ": cannot open frame file (" + std::strerror(errno) + ")");
  }
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    const int err = errno;
    ::close(fd);
    return make_error(frame_context(i) + ": cannot stat frame file (" + std::strerror(err) + ")");
  }
  auto& bytes = buffers->file_bytes;
  bytes.resize(static_cast<size_t>(st.st_size));
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::read(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int err = n < 0 ? errno : 0;
      ::close(fd);
      return make_error(
          frame_context(i) + ": read error" +
          (err ? std::string(" (") + std::strerror(err) + ")" : std::string(" (file shrank)")));
    }
    done += static_cast<size_t>(n);
  }
  ::close(fd);

  auto info = inspect_frame_bytes(bytes.data(), bytes.size());
  if (!info) return make_error(frame_context(i) + ": " + info.error().message);
  auto supported = check_supported_frame(*info);
  if (!supported) return make_error(frame_context(i) + ": " + supported.error().message);
  const CameraIntrinsics& k = camera_.intrinsics;
  if (info->width != k.width || info->height != k.height) {
    return make_error(frame_context(i) + ": image is " + std::to_string(info->width) + "x" +
                      std::to_string(info->height) + ", recording.yaml says " +
                      std::to_string(k.width) + "x" + std::to_string(k.height));
  }
  buffers->info = *info;
  return {};
}

Result<void> RecordingReader::check_frame(size_t i) const {
  return read_frame_file(i, scratch_.get());
}

Result<void> RecordingReader::load_frame(size_t i, Image* out) const {
  return load_frame(i, out, scratch_.get());
}

namespace {

// Why a frame could not be decoded when memory ran out: a decoder that fails
// to allocate inside the library may only say the data is corrupt (issue
// 28), so a failed decode tries to allocate what it needed before blaming
// the file.
std::string out_of_memory_text(int width, int height) {
  const size_t bytes = decoded_frame_bytes(width, height);
  return "not enough memory to decode this " + std::to_string(width) + "x" +
         std::to_string(height) + " frame (" + std::to_string(bytes >> 20) +
         " MiB decoded, twice that while decoding): raise the address-space limit (ulimit -v, "
         "LimitAS=) or decode on fewer threads (--decode-threads)";
}

bool memory_for(const FrameFileInfo& info) {
  const size_t bytes = decoded_frame_bytes(info.width, info.height);
  std::unique_ptr<uint8_t[]> probe(new (std::nothrow) uint8_t[2 * bytes]);
  return probe != nullptr;
}

}  // namespace

Result<void> RecordingReader::load_frame(size_t i, Image* out, DecodeBuffers* buffers) const {
  try {
    return decode_frame(i, out, buffers);
  } catch (const std::bad_alloc&) {
    // The message needs memory too; if there is none, the bad_alloc of its
    // making goes to the caller (FramePrefetcher names it later).
    return make_error(out_of_memory_error(i));
  }
}

std::string RecordingReader::out_of_memory_error(size_t i) const {
  return frame_context(i) + ": " +
         out_of_memory_text(camera_.intrinsics.width, camera_.intrinsics.height);
}

Result<void> RecordingReader::decode_frame(size_t i, Image* out, DecodeBuffers* buffers) const {
  auto read = read_frame_file(i, buffers);
  if (!read) return read;
  const auto& bytes = buffers->file_bytes;
  const FrameFileInfo& info = buffers->info;
  // Grey files decode to GREY, colour and palette files to RGB24.
  const auto decoded =
      info.encoding == FrameEncoding::kPng
          ? codec::decode_png(bytes.data(), bytes.size(), out)
          : buffers->jpeg.decode(bytes.data(), bytes.size(),
                                 info.channels == 1 ? PixelFormat::kGray8 : PixelFormat::kRgb24,
                                 out);
  if (!decoded) {
    return make_error(
        frame_context(i) + ": " +
        (memory_for(info) ? decoded.error().message : out_of_memory_text(info.width, info.height)));
  }
  if (out->width() != info.width || out->height() != info.height) {
    return make_error(frame_context(i) + ": decoded " + std::to_string(out->width()) + "x" +
                      std::to_string(out->height()) + " from a " + std::to_string(info.width) +
                      "x" + std::to_string(info.height) + " header");
  }
  return {};
}

}  // namespace ceilpose
