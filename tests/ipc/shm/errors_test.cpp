// Every way opening or creating a segment can fail gives a typed error and a
// message naming the segment (and its size or mode where that is the cause).
#include <fcntl.h>
#include <grp.h>
#include <gtest/gtest.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <vector>

#include "ipc/shm/shm_layout.h"
#include "ipc/shm/shm_pose_reader.h"
#include "ipc/shm/shm_pose_writer.h"
#include "shm_test_support.h"

namespace ceilpose {
namespace {

using shm::ShmErrc;
using test::ForkedChild;

class ShmErrors : public test::ShmFixture {};

constexpr uid_t kNobody = 65534;

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// Overwrites bytes of an existing segment, as a foreign or future writer would.
void patch_segment(const std::string& name, size_t offset, const void* bytes, size_t size) {
  const int fd = ::shm_open(name.c_str(), O_RDWR, 0);
  ASSERT_GE(fd, 0);
  void* p = ::mmap(nullptr, sizeof(shm::Segment), PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  ASSERT_NE(p, MAP_FAILED);
  std::memcpy(static_cast<char*>(p) + offset, bytes, size);
  ::munmap(p, sizeof(shm::Segment));
  ::close(fd);
}

TEST_F(ShmErrors, OpenOfMissingSegmentIsNotFoundNamingIt) {
  ShmErrc code = ShmErrc::kOk;
  auto reader = ShmPoseReader::open(name(), &code);
  ASSERT_FALSE(reader);
  EXPECT_EQ(code, ShmErrc::kNotFound);
  EXPECT_TRUE(contains(reader.error().message, name())) << reader.error().message;
}

TEST_F(ShmErrors, OpenOfOtherAbiVersionIsRefusedNamingBothVersions) {
  ASSERT_NO_FATAL_FAILURE(start());
  const uint32_t future_abi = shm::kAbiVersion + 1;
  patch_segment(name(), offsetof(shm::SegmentHeader, abi_version), &future_abi, sizeof future_abi);
  ShmErrc code = ShmErrc::kOk;
  auto reader = ShmPoseReader::open(name(), &code);
  ASSERT_FALSE(reader);
  EXPECT_EQ(code, ShmErrc::kAbiMismatch);
  EXPECT_TRUE(contains(reader.error().message, "ABI version " + std::to_string(future_abi)))
      << reader.error().message;
  EXPECT_TRUE(contains(reader.error().message, "version " + std::to_string(shm::kAbiVersion)));
  EXPECT_TRUE(contains(reader.error().message, name()));
}

TEST_F(ShmErrors, OpenOfSegmentWithWrongSizeIsRefusedNamingBothSizes) {
  ASSERT_NO_FATAL_FAILURE(start());
  const int fd = ::shm_open(name().c_str(), O_RDWR, 0);
  ASSERT_GE(fd, 0);
  const size_t bigger = sizeof(shm::Segment) + 4096;
  ASSERT_EQ(::ftruncate(fd, static_cast<off_t>(bigger)), 0);
  ::close(fd);
  ShmErrc code = ShmErrc::kOk;
  auto reader = ShmPoseReader::open(name(), &code);
  ASSERT_FALSE(reader);
  EXPECT_EQ(code, ShmErrc::kBadSize);
  EXPECT_TRUE(contains(reader.error().message, std::to_string(bigger))) << reader.error().message;
  EXPECT_TRUE(contains(reader.error().message, std::to_string(sizeof(shm::Segment))));
}

TEST_F(ShmErrors, OpenOfTinySegmentIsBadSize) {
  const int fd = ::shm_open(name().c_str(), O_RDWR | O_CREAT | O_EXCL, 0600);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::ftruncate(fd, 4), 0);
  ::close(fd);
  ShmErrc code = ShmErrc::kOk;
  auto reader = ShmPoseReader::open(name(), &code);
  ASSERT_FALSE(reader);
  EXPECT_EQ(code, ShmErrc::kBadSize);
  EXPECT_TRUE(contains(reader.error().message, "4 bytes")) << reader.error().message;
}

TEST_F(ShmErrors, OpenOfForeignSegmentIsBadMagic) {
  ASSERT_NO_FATAL_FAILURE(start());
  const uint64_t other = 0x0123456789abcdefULL;
  patch_segment(name(), 0, &other, sizeof other);
  ShmErrc code = ShmErrc::kOk;
  auto reader = ShmPoseReader::open(name(), &code);
  ASSERT_FALSE(reader);
  EXPECT_EQ(code, ShmErrc::kBadMagic);
}

TEST_F(ShmErrors, OpenOfEmptySegmentIsNotReady) {
  const int fd = ::shm_open(name().c_str(), O_RDWR | O_CREAT | O_EXCL, 0600);
  ASSERT_GE(fd, 0);
  ::close(fd);
  ShmErrc code = ShmErrc::kOk;
  auto reader = ShmPoseReader::open(name(), &code);
  ASSERT_FALSE(reader);
  EXPECT_EQ(code, ShmErrc::kNotReady);
}

TEST_F(ShmErrors, InvalidNameIsRejectedByReaderAndWriter) {
  for (const std::string& bad :
       std::vector<std::string>{"", "ceilpose", "/", "/a/b", std::string(300, 'x')}) {
    ShmErrc code = ShmErrc::kOk;
    auto reader = ShmPoseReader::open(bad, &code);
    EXPECT_FALSE(reader);
    EXPECT_EQ(code, ShmErrc::kInvalidArgument) << bad;
    ShmOptions options;
    options.name = bad;
    auto writer = ShmPoseWriter::create(options, &code);
    EXPECT_FALSE(writer);
    EXPECT_EQ(code, ShmErrc::kInvalidArgument) << bad;
  }
}

TEST_F(ShmErrors, UnprivilegedReaderIsRefusedWithPermissionErrorNamingMode) {
  ASSERT_NO_FATAL_FAILURE(start());
  if (::geteuid() != 0) GTEST_SKIP() << "needs root to switch to uid " << kNobody;
  constexpr int kSetuidFailed = 77;
  ForkedChild child([&](ForkedChild&) {
    if (::setgroups(0, nullptr) != 0 || ::setgid(kNobody) != 0 || ::setuid(kNobody) != 0) {
      return kSetuidFailed;
    }
    ShmErrc code = ShmErrc::kOk;
    auto reader = ShmPoseReader::open(name(), &code);
    if (reader) return 1;
    if (code != ShmErrc::kPermission) return 2;
    const std::string& m = reader.error().message;
    if (!contains(m, name()) || !contains(m, "0640") || !contains(m, "uid 65534")) return 3;
    return 0;
  });
  const int status = child.wait_exit(20'000);
  if (status == kSetuidFailed) GTEST_SKIP() << "setuid(" << kNobody << ") failed here";
  EXPECT_EQ(status, 0) << "1: opened, 2: wrong code, 3: message lacks name/mode/uid";
}

TEST_F(ShmErrors, SegmentModeIs0640EvenWithRestrictiveUmask) {
  const mode_t old_mask = ::umask(077);
  ASSERT_NO_FATAL_FAILURE(start());
  ::umask(old_mask);
  struct stat st {};
  ASSERT_EQ(::stat(("/dev/shm" + name()).c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0640u);
  ASSERT_EQ(::stat(("/dev/shm" + shm::wake_segment_name(name())).c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0660u);
}

TEST_F(ShmErrors, ConfiguredGroupOwnsTheSegment) {
  const struct group* g = ::getgrnam("daemon");
  if (g == nullptr) GTEST_SKIP() << "no group 'daemon' on this system";
  if (::geteuid() != 0) GTEST_SKIP() << "needs root to give a segment to another group";
  ShmOptions options;
  options.name = name();
  options.group = "daemon";
  auto writer = ShmPoseWriter::create(options);
  ASSERT_TRUE(writer) << writer.error().message;
  struct stat st {};
  ASSERT_EQ(::stat(("/dev/shm" + name()).c_str(), &st), 0);
  EXPECT_EQ(st.st_gid, g->gr_gid);
}

TEST_F(ShmErrors, UnknownGroupIsAnErrorNamingIt) {
  ShmOptions options;
  options.name = name();
  options.group = "no-such-group-ceilpose";
  ShmErrc code = ShmErrc::kOk;
  auto writer = ShmPoseWriter::create(options, &code);
  ASSERT_FALSE(writer);
  EXPECT_EQ(code, ShmErrc::kNoGroup);
  EXPECT_TRUE(contains(writer.error().message, "no-such-group-ceilpose"));
  // Nothing is half-created.
  ShmErrc open_code = ShmErrc::kOk;
  EXPECT_FALSE(ShmPoseReader::open(name(), &open_code));
  EXPECT_EQ(open_code, ShmErrc::kNotFound);
}

}  // namespace
}  // namespace ceilpose
