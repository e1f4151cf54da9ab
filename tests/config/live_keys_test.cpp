// SIGHUP's live keys are one table (config_schema.h): what the daemon copies
// on a reload, and what the shipped configuration, the unit and the service
// documentation say about it.
#include <gtest/gtest.h>

#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include "config/service_config.h"

namespace ceilpose {
namespace {

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// Comment markers and line breaks out, so that a wrapped sentence is one:
// each line break with the indentation and '#' after it becomes one space,
// and runs of spaces one space. (No std::regex: GCC 12 warns inside it
// under the sanitizers, and warnings are errors.)
std::string flattened(const std::string& text) {
  std::string out;
  for (size_t i = 0; i < text.size(); ++i) {
    char c = text[i];
    if (c == '\n') {
      while (i + 1 < text.size() && (text[i + 1] == ' ' || text[i + 1] == '\t')) ++i;
      if (i + 1 < text.size() && text[i + 1] == '#') ++i;
      c = ' ';
    }
    if (c == ' ' && !out.empty() && out.back() == ' ') continue;
    out += c;
  }
  return out;
}

std::string section_of(const std::string& key) { return key.substr(0, key.find('.')); }

TEST(LiveKeys, AReloadTakesExactlyTheLiveKeysFromTheNewFile) {
  const ServiceConfig running = default_config();
  // One changed key in every section, and both keys that need a restart.
  auto next = apply_overrides(running, {{"camera.fx", "600", "t"},
                                        {"camera.width", "320", "t"},
                                        {"camera.height", "240", "t"},
                                        {"camera.calibration_file", "c.yaml", "t"},
                                        {"mount.yaw_rad", "0.1", "t"},
                                        {"ceiling.grid_m", "0.5", "t"},
                                        {"detector.dark_max_value", "100", "t"},
                                        {"positioning.mode", "lsq", "t"},
                                        {"filter.enabled", "false", "t"},
                                        {"capture.fps", "15", "t"},
                                        {"ipc.stale_after_ms", "900", "t"},
                                        {"dds.domain_id", "7", "t"},
                                        {"fleet.capacity", "300", "t"},
                                        {"logging.level", "debug", "t"},
                                        {"watchdog.max_stall_ms", "900", "t"}});
  ASSERT_TRUE(next.ok()) << next.error().message;
  const auto before = config_values(running);
  const auto after = config_values(*next);
  const auto applied = config_values(with_live_keys(running, *next));
  ASSERT_EQ(before.size(), applied.size());
  std::set<std::string> sections_changed;
  for (size_t i = 0; i < before.size(); ++i) {
    const std::string& key = before[i].first;
    if (before[i].second == after[i].second) {
      EXPECT_EQ(applied[i].second, before[i].second) << key;
      continue;
    }
    sections_changed.insert(section_of(key));
    EXPECT_EQ(applied[i].second, is_live_key(key) ? after[i].second : before[i].second)
        << key << (is_live_key(key) ? " is live" : " needs a restart");
  }
  std::set<std::string> every_section;
  for (const std::string& key : config_key_paths()) every_section.insert(section_of(key));
  EXPECT_EQ(sections_changed, every_section) << "the test must change a key of every section";
}

TEST(LiveKeys, TheImageSizeNeedsARestartAndTheRestOfTheCameraDoesNot) {
  EXPECT_FALSE(is_live_key("camera.width"));
  EXPECT_FALSE(is_live_key("camera.height"));
  EXPECT_TRUE(is_live_key("camera.fx"));
  EXPECT_TRUE(is_live_key("ceiling.map"));
  EXPECT_FALSE(is_live_key("capture.fps"));
  EXPECT_FALSE(is_live_key("cameraX.fx"));
}

TEST(LiveKeys, TheConfigurationTheUnitAndTheServiceDocumentSayTheSame) {
  const std::string phrase = "applies " + live_keys_phrase();
  for (const char* file :
       {"/config/ceilpose.yaml", "/systemd/ceilposed.service.in", "/docs/service.md"}) {
    const std::string text = flattened(read_text(std::string(CEILPOSE_SOURCE_DIR) + file));
    EXPECT_NE(text.find(phrase), std::string::npos) << file << " must say: " << phrase;
  }
}

TEST(LiveKeys, EachSectionOfTheShippedConfigurationSaysWhetherItIsLive) {
  const std::string yaml = read_text(std::string(CEILPOSE_SOURCE_DIR) + "/config/ceilpose.yaml");
  std::set<std::string> sections;
  for (const std::string& key : config_key_paths()) sections.insert(section_of(key));
  for (const std::string& section : sections) {
    const size_t at = yaml.find("\n" + section + ":\n");
    ASSERT_NE(at, std::string::npos) << section;
    // The comment block just above the section.
    const size_t start = yaml.rfind("\n\n", at);
    const std::string comment = yaml.substr(start, at - start);
    const bool live = is_live_key(section + ".any");
    EXPECT_NE(comment.find(live ? "Live on reload" : "Needs a restart"), std::string::npos)
        << section << ": " << comment;
  }
}

}  // namespace
}  // namespace ceilpose
