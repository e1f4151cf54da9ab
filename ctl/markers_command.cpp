// ceilposectl markers: printable sheets of the ceiling's markers (SPEC §10),
// one file per marker plus the plan of the whole ceiling.
#include <sys/stat.h>

#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <sstream>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "config/service_config.h"
#include "ctl/command_registry.h"
#include "print/marker_sheets.h"

namespace ceilpose::ctl {
namespace {

struct MarkersArgs {
  std::string out_dir;
  std::string config_file;
  std::string codes = "all";
  std::string format = "svg";
};

// "all" or "I,J;I,J;...": every code within the layout, or an error message.
bool parse_codes(const std::string& text, int codes, std::vector<std::array<int, 2>>* out,
                 std::string* error) {
  out->clear();
  if (text == "all") {
    for (int j = 0; j < codes; ++j)
      for (int i = 0; i < codes; ++i) out->push_back({i, j});
    return true;
  }
  std::stringstream list(text);
  // Each side read whole and range-checked as it is: sscanf's %d wrapped
  // 4294967299 to 3 and printed marker_3_5.
  const auto code_of = [codes](std::string_view text, int* value) {
    while (!text.empty() && text.front() == ' ') text.remove_prefix(1);
    while (!text.empty() && text.back() == ' ') text.remove_suffix(1);
    long long v = -1;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
    if (ec == std::errc::result_out_of_range)
      v = -1;
    else if (ec != std::errc{} || end != text.data() + text.size() || text.empty())
      return false;
    *value = v >= 0 && v < codes ? static_cast<int>(v) : -1;
    return true;
  };
  for (std::string item; std::getline(list, item, ';');) {
    const size_t comma = item.find(',');
    int i = -1, j = -1;
    if (comma == std::string::npos || !code_of(std::string_view(item).substr(0, comma), &i) ||
        !code_of(std::string_view(item).substr(comma + 1), &j)) {
      *error = "--codes: '" + item + "' is not I,J (e.g. 3,5;0,7 or all)";
      return false;
    }
    if (i < 0 || j < 0) {
      *error = "--codes: '" + item + "' is outside the ceiling's 0.." + std::to_string(codes - 1) +
               " codes";
      return false;
    }
    out->push_back({i, j});
  }
  if (out->empty()) {
    *error = "--codes: no code given";
    return false;
  }
  return true;
}

void run_markers(const MarkersArgs& args) {
  ServiceConfig config = default_config();
  if (!args.config_file.empty()) {
    auto loaded = load_config_file(args.config_file);
    if (!loaded) {
      std::fprintf(stderr, "ceilposectl markers: %s\n", loaded.error().message.c_str());
      return set_exit_code(kExitBadInput);
    }
    config = std::move(loaded).value();
  }
  const CeilingLayout& layout = config.pipeline.layout;
  std::vector<std::array<int, 2>> codes;
  std::string error;
  if (!parse_codes(args.codes, layout.codes(), &codes, &error)) {
    std::fprintf(stderr, "ceilposectl markers: %s\n", error.c_str());
    return set_exit_code(kExitUsage);
  }
  // "Created if missing", parents included (markers --out a/b/c).
  std::error_code made;
  std::filesystem::create_directories(args.out_dir, made);
  if (made) {
    std::fprintf(stderr, "ceilposectl markers: %s: cannot create: %s\n", args.out_dir.c_str(),
                 made.message().c_str());
    return set_exit_code(kExitFailure);
  }
  const SheetFormat format = args.format == "pdf" ? SheetFormat::kPdf : SheetFormat::kSvg;
  for (size_t k = 0; k < codes.size(); ++k) {
    const auto [i, j] = codes[k];
    const std::string path =
        args.out_dir + "/marker_" + std::to_string(i) + "_" + std::to_string(j) + "." + args.format;
    if (auto wrote = write_marker_sheet(path, layout, i, j, format); !wrote) {
      std::fprintf(stderr, "ceilposectl markers: %s\n", wrote.error().message.c_str());
      return set_exit_code(kExitFailure);
    }
    std::fprintf(stderr, "\rmarkers: %zu/%zu sheets", k + 1, codes.size());
  }
  std::fputc('\n', stderr);
  const std::string plan = args.out_dir + "/layout.svg";
  if (auto wrote = write_ceiling_plan(plan, layout); !wrote) {
    std::fprintf(stderr, "ceilposectl markers: %s\n", wrote.error().message.c_str());
    return set_exit_code(kExitFailure);
  }
  const SheetGeometry g = marker_sheet_geometry(layout);
  std::fprintf(stderr,
               "markers: wrote %zu %s sheets of %.0f x %.0f mm (marker %.1f x %.1f mm, 1:1; print "
               "at 100 %%, no fit-to-page) and %s to %s\n",
               codes.size(), args.format.c_str(), g.page_width_mm, g.page_height_mm,
               2000.0 * layout.rect_width_m, 1000.0 * layout.rect_height_m, "layout.svg",
               args.out_dir.c_str());
  set_exit_code(kExitOk);
}

void add_markers_command(CLI::App& app) {
  auto args = std::make_shared<MarkersArgs>();
  CLI::App* cmd = app.add_subcommand(
      "markers",
      "Write printable marker sheets (SPEC §10): marker_<i>_<j>.svg (or .pdf), one per marker, "
      "1:1 in millimetres, drawn from the configured layout and colours as seen from below "
      "(sheet top = North: red on the left, most significant bit at the top), with the code, a "
      "North arrow and centre ticks outside the outline; and layout.svg, the plan of the whole "
      "ceiling from below. Glue each sheet printed face down, top edge North, centre ticks on "
      "its rail intersection (docs/commissioning.md).\n"
      "Exit 0 ok, 1 a file could not be written, 2 usage, 4 malformed configuration.");
  cmd->add_option("--out", args->out_dir, "Directory to write into (created if missing)")
      ->required();
  cmd->add_option("--config", args->config_file, "Configuration (ceiling layout and colours)");
  cmd->add_option("--codes", args->codes, "all, or I,J[;I,J...] (e.g. 3,5;0,7)")
      ->capture_default_str();
  cmd->add_option("--format", args->format, "svg or pdf")
      ->check(CLI::IsMember({"svg", "pdf"}))
      ->capture_default_str();
  cmd->callback([args] { run_markers(*args); });
}

const CommandRegistrar kMarkersRegistrar{"markers", &add_markers_command};

}  // namespace
}  // namespace ceilpose::ctl
