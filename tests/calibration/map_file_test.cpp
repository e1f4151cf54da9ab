#include "calibration/map_file.h"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <string>

#include "calibration/calibration_files.h"
#include "tests/support/temp_file.h"

namespace ceilpose {
namespace {

using test::write_temp;

const char* kHeader =
    "format: ceilpose-map\nversion: 1\nceiling:\n  height_m: 2.4384\n  grid_m: 0.6096\n  bits: "
    "3\nmarkers:\n";

TEST(MapFile, ReadsTheSpecExample) {
  const std::string path = write_temp(
      "spec.yaml", std::string(kHeader) +
                       "  - code: [3, 5]\n    x_m: 1.8301\n    y_m: 3.0467\n    yaw_rad: "
                       "0.0121\n    sigma_m: 0.0004\n    sigma_yaw_rad: 0.0006\n    "
                       "observations: 143\n");
  auto map = read_map_file(path, CeilingLayout{});
  ASSERT_TRUE(map) << map.error().message;
  EXPECT_EQ(map->present_count(), 1);
  const MarkerPlacement* p = map->find(3, 5);
  ASSERT_NE(p, nullptr);
  EXPECT_DOUBLE_EQ(p->x_m, 1.8301);
  EXPECT_DOUBLE_EQ(p->y_m, 3.0467);
  EXPECT_DOUBLE_EQ(p->yaw_rad, 0.0121);
  EXPECT_DOUBLE_EQ(p->sigma_m, 0.0004);
  EXPECT_DOUBLE_EQ(p->sigma_yaw_rad, 0.0006);
  EXPECT_EQ(p->observations, 143);
  EXPECT_EQ(map->find(3, 4), nullptr) << "a marker the map does not list is not on the ceiling";
  EXPECT_TRUE(map->surveyed());
}

TEST(MapFile, WrittenMapReadsBackToTheMicrometre) {
  const CeilingLayout layout;
  CeilingMap map(layout);
  MarkerPlacement p = *map.find(2, 6);
  p.x_m += 0.0123456;
  p.y_m -= 0.0098765;
  p.yaw_rad = -0.0234567;
  p.sigma_m = 0.00031;
  p.sigma_yaw_rad = 0.00042;
  p.observations = 17;
  map.set(2, 6, p);
  const std::string path = write_temp("round.yaml", "");
  ASSERT_TRUE(write_map_file(path, map, layout));
  auto back = read_map_file(path, layout);
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->present_count(), 64);
  const MarkerPlacement* q = back->find(2, 6);
  ASSERT_NE(q, nullptr);
  EXPECT_NEAR(q->x_m, p.x_m, 1e-6);
  EXPECT_NEAR(q->y_m, p.y_m, 1e-6);
  EXPECT_NEAR(q->yaw_rad, p.yaw_rad, 1e-7);
  EXPECT_NEAR(q->sigma_m, p.sigma_m, 1e-7);
  EXPECT_EQ(q->observations, 17);
}

struct BadMap {
  const char* name;
  std::string text;
  const char* message;  // expected after "FILE:"
};

class MalformedMap : public ::testing::TestWithParam<BadMap> {};

TEST_P(MalformedMap, IsRejectedNamingFileLineAndEntry) {
  const std::string path = write_temp(std::string(GetParam().name) + ".yaml", GetParam().text);
  auto map = read_map_file(path, CeilingLayout{});
  ASSERT_FALSE(map);
  EXPECT_NE(map.error().message.find(path + ":"), std::string::npos) << map.error().message;
  EXPECT_NE(map.error().message.find(GetParam().message), std::string::npos) << map.error().message;
}

const std::string kOne = "  - code: [1, 2]\n    x_m: 0.61\n    y_m: 1.22\n";

// The whole nominal grid moved by (dx, dy) and turned by turn_deg about the
// origin: a map out of SPEC §8's datum.
std::string moved_grid(double dx_m, double dy_m, double turn_deg) {
  std::string out = kHeader;
  const double c = std::cos(turn_deg * M_PI / 180.0), s = std::sin(turn_deg * M_PI / 180.0);
  for (int j = 0; j < 8; ++j)
    for (int i = 0; i < 8; ++i) {
      const double x = i * 0.6096, y = j * 0.6096;
      out += "  - code: [" + std::to_string(i) + ", " + std::to_string(j) +
             "]\n    x_m: " + std::to_string(c * x - s * y + dx_m) +
             "\n    y_m: " + std::to_string(s * x + c * y + dy_m) + "\n";
    }
  return out;
}

INSTANTIATE_TEST_SUITE_P(
    Kinds, MalformedMap,
    ::testing::Values(
        BadMap{"Syntax", std::string(kHeader) + "  - code: [1, 2\n", "YAML syntax error"},
        BadMap{"NotAMap", "- 1\n- 2\n", ":1: expected a YAML mapping"},
        BadMap{"Format", "format: ceilpose-recording\nversion: 1\nmarkers:\n" + kOne,
               ":1: format 'ceilpose-recording' is not 'ceilpose-map'"},
        BadMap{"Version", "format: ceilpose-map\nversion: 2\nmarkers:\n" + kOne,
               ":2: unsupported version 2"},
        // Issue 28, defect 17: a quoted version was read as the number.
        BadMap{"QuotedVersion", "format: ceilpose-map\nversion: \"1\"\nmarkers:\n" + kOne,
               "must be an integer, found the string '1'"},
        BadMap{"Twice", std::string(kHeader) + kOne + kOne,
               ":11: markers[1] (code [1, 2]): code listed twice"},
        // Found by fuzz_map: yaml-cpp threw for the missing key (a crash).
        BadMap{"MarkerWithoutCode", std::string(kHeader) + "  - \n    observations: 143\n",
               ":9: markers[0].code must be a pair of integers [i, j]"},
        BadMap{"OutsideBits", std::string(kHeader) + "  - code: [8, 0]\n    x_m: 0\n    y_m: 0\n",
               ":8: markers[0] (code [8, 0]): code outside the ceiling's 8 x 8 codes"},
        BadMap{"Negative", std::string(kHeader) + "  - code: [-1, 0]\n    x_m: 0\n    y_m: 0\n",
               "code outside"},
        BadMap{"NotFinite", std::string(kHeader) + "  - code: [1, 2]\n    x_m: .nan\n    y_m: 1\n",
               ":9: key 'markers[0] (code [1, 2]).x_m' must be a finite number, found '.nan'"},
        BadMap{"Infinite", std::string(kHeader) + "  - code: [1, 2]\n    x_m: 1\n    y_m: .inf\n",
               "must be a finite number"},
        BadMap{"MissingCentre", std::string(kHeader) + "  - code: [1, 2]\n    x_m: 1\n",
               ":8: missing key 'markers[0] (code [1, 2]).y_m'"},
        BadMap{"NegativeSigma", std::string(kHeader) + kOne + "    sigma_m: -0.001\n",
               "markers[0] (code [1, 2]).sigma_m is negative"},
        BadMap{"UnknownKey", std::string(kHeader) + kOne + "    z_m: 2.4\n",
               ":11: unknown key 'markers[0].z_m'"},
        BadMap{"BadCode", std::string(kHeader) + "  - code: [1]\n    x_m: 1\n    y_m: 1\n",
               "markers[0].code must be a pair of integers [i, j]"},
        BadMap{"OtherBits",
               "format: ceilpose-map\nversion: 1\nceiling:\n  bits: 4\nmarkers:\n" + kOne,
               ":4: ceiling.bits is 4 but the configuration's ceiling.bits is 3"},
        BadMap{"OtherHeight",
               "format: ceilpose-map\nversion: 1\nceiling:\n  height_m: 3.0\nmarkers:\n" + kOne,
               "ceiling.height_m is 3.000000 m but the configuration's ceiling.height_m is "
               "2.438400 m"},
        // Issue 28, defect 4: 1e154 gave valid poses with a NaN covariance.
        BadMap{"HugeSigma", std::string(kHeader) + kOne + "    sigma_m: 1e154\n",
               "markers[0] (code [1, 2]).sigma_m is 1e+154, over 1: a marker known no better"},
        // Issue 28, defect 5: a moved or turned map moved every pose with it.
        BadMap{"Shifted", moved_grid(1.0, 0.0, 0.0),
               "breaks SPEC §8's datum: the best rigid fit of its 64 centres onto the nominal "
               "grid moves them by (-1000.0, "},
        BadMap{"Turned", moved_grid(0.0, 0.0, 10.0), "turns them by -10.000 deg"},
        // Issue 28, defect 12: a 10 kB "billion laughs" map took 52 s.
        BadMap{
            "AliasBomb",
            "format: ceilpose-map\nversion: 1\na: &a [x, x, x, x, x, x, x, x, x]\n"
            "b: &b [*a, *a, *a, *a, *a, *a, *a, *a, *a]\nc: &c [*b, *b, *b, *b, *b, *b, *b, *b]\n"
            "markers:\n" +
                kOne,
            ":4: YAML aliases (*name) are not accepted"},
        // Issue 28, defect 13: the entries a 3-bit ceiling's map can hold.
        BadMap{"MoreEntriesThanAnyMap",
               std::string(kHeader) +
                   [] {
                     std::string many;
                     for (int k = 0; k < 200; ++k) many += kOne;
                     return many;
                   }(),
               ": more than 1344 YAML entries (values, lists, mappings), more than a file of "
               "this kind can hold"},
        BadMap{"NoMarkers", "format: ceilpose-map\nversion: 1\nmarkers: []\n",
               "key 'markers' must be a non-empty list"},
        BadMap{"Empty", "", ":1: expected a YAML mapping"}),
    [](const auto& info) { return std::string(info.param.name); });

// Issue 28, defect 13: an 11 MB map needed ~780 MB to parse, and a reload
// under a memory limit ended the daemon. Refused now by its entry count, in
// one streaming pass.
TEST(MapFile, AnElevenMegabyteMapIsRefusedWithoutLoadingIt) {
  std::string text = kHeader;
  while (text.size() < (size_t{11} << 20)) text += kOne;
  const std::string path = write_temp("huge.yaml", text);
  rusage before{};
  ::getrusage(RUSAGE_SELF, &before);
  auto map = read_map_file(path, CeilingLayout{});
  rusage after{};
  ::getrusage(RUSAGE_SELF, &after);
  ASSERT_FALSE(map);
  EXPECT_NE(map.error().message.find("more than 1344 YAML entries"), std::string::npos)
      << map.error().message;
  EXPECT_LT(after.ru_maxrss - before.ru_maxrss, 200 * 1024) << "peak RSS grew (KiB)";
}

TEST(MapFile, ADirectoryOrAMissingFileIsAnError) {
  auto dir = read_map_file(::testing::TempDir(), CeilingLayout{});
  ASSERT_FALSE(dir);
  EXPECT_NE(dir.error().message.find("it is a directory"), std::string::npos);
  auto missing = read_map_file(::testing::TempDir() + "no-such-map.yaml", CeilingLayout{});
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("no-such-map.yaml: cannot read ceiling map"),
            std::string::npos)
      << missing.error().message;
}

TEST(CalibrationFiles, LoadTheMapIntoThePipelineAndNothingOnError) {
  PipelineConfig pipeline;
  const std::string good = write_temp("good.yaml", std::string(kHeader) + kOne);
  ASSERT_TRUE(load_calibration_files({"", good}, "the capture", &pipeline));
  ASSERT_NE(pipeline.map, nullptr);
  EXPECT_EQ(pipeline.map->present_count(), 1);
  const std::string bad = write_temp("bad.yaml", std::string(kHeader) + kOne + kOne);
  PipelineConfig untouched;
  EXPECT_FALSE(load_calibration_files({"", bad}, "the capture", &untouched));
  EXPECT_EQ(untouched.map, nullptr);
}

TEST(CeilingMapDatum, TheBestFitRigidMotionOfAShiftedTurnedGridUndoesIt) {
  const CeilingLayout layout;
  CeilingMap map(layout);
  const PlaneMotion moved{0.01, 0.02, -0.03};
  move_map(moved, &map);
  const PlaneMotion back = datum_motion(map, layout);
  move_map(back, &map);
  for (int j = 0; j < 8; ++j)
    for (int i = 0; i < 8; ++i) {
      const MarkerPlacement* p = map.find(i, j);
      EXPECT_NEAR(p->x_m, i * layout.grid_m, 1e-12);
      EXPECT_NEAR(p->y_m, j * layout.grid_m, 1e-12);
      EXPECT_NEAR(p->yaw_rad, 0.0, 1e-12);
    }
}

}  // namespace
}  // namespace ceilpose
