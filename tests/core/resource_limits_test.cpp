// Issue 15: ceilposed under `ulimit -n 12` or `ulimit -v 300000` crashed
// inside Cyclone DDS (139, 134); the limits are now checked first.
#include "core/resource_limits.h"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <string>

namespace ceilpose {
namespace {

// Lowers one soft limit for the test's lifetime.
class ScopedLimit {
 public:
  ScopedLimit(int resource, rlim_t soft) : resource_(resource) {
    ::getrlimit(resource_, &saved_);
    rlimit lowered = saved_;
    lowered.rlim_cur = soft;
    ok_ = ::setrlimit(resource_, &lowered) == 0;
  }
  ~ScopedLimit() { ::setrlimit(resource_, &saved_); }
  bool ok() const { return ok_; }

 private:
  int resource_;
  rlimit saved_{};
  bool ok_ = false;
};

TEST(ResourceLimits, TooFewFileDescriptorsAreNamedWithTheSettingThatRaisesThem) {
  EXPECT_EQ(resource_limit_problem({32, 0}), "") << "the test's own limits suffice";
  ScopedLimit files(RLIMIT_NOFILE, 20);
  ASSERT_TRUE(files.ok());
  const std::string problem = resource_limit_problem({32, 0});
  EXPECT_NE(problem.find("the open-file limit is 20 (ulimit -n)"), std::string::npos) << problem;
  EXPECT_NE(problem.find("needs 32 more"), std::string::npos) << problem;
  EXPECT_NE(problem.find("LimitNOFILE="), std::string::npos) << problem;
}

TEST(ResourceLimits, TooLittleAddressSpaceIsNamedInMiB) {
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  GTEST_SKIP() << "sanitizers reserve terabytes of address space";
#endif
  ScopedLimit space(RLIMIT_AS, rlim_t{300} << 20);
  if (!space.ok()) GTEST_SKIP() << "this process already maps more than 300 MiB";
  const std::string problem = resource_limit_problem({0, 512});
  EXPECT_NE(problem.find("the address-space limit is 300 MiB (ulimit -v 307200); needs at least "
                         "512 MiB"),
            std::string::npos)
      << problem;
  EXPECT_EQ(resource_limit_problem({0, 256}), "");
}

}  // namespace
}  // namespace ceilpose
