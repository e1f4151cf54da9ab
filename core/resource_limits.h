#pragma once
// A process started under limits too tight for it (ulimit -v / LimitAS=,
// ulimit -n / LimitNOFILE=) used to die inside a library: Cyclone DDS
// aborts when it cannot start a thread and crashes when it cannot open a
// socket. Checked before anything starts, the limit is named instead.
#include <cstddef>
#include <string>

namespace ceilpose {

struct ResourceNeeds {
  size_t file_descriptors = 0;   // free descriptors beyond those open now
  size_t address_space_mib = 0;  // RLIMIT_AS, when limited
};

// Empty when the limits allow `needs`, else which limit, its value, the
// need and the systemd setting that raises it.
std::string resource_limit_problem(const ResourceNeeds& needs);

}  // namespace ceilpose
