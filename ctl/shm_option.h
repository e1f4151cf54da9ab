#pragma once
// --shm of the commands that read the daemon's segment (pose, watch, status):
// a malformed name is a usage error (exit 2), said before anything is opened.
#include <CLI/CLI.hpp>
#include <string>

#include "ipc/shm/shm_common.h"

namespace ceilpose::ctl {

inline CLI::Option* add_shm_option(CLI::App* cmd, std::string* shm) {
  return cmd->add_option("--shm", *shm, "shared-memory segment name")
      ->capture_default_str()
      ->check(CLI::Validator(
          [](const std::string& value) {
            return shm::valid_shm_name(value) ? std::string()
                                              : std::string("must be ") + shm::kShmNameRule;
          },
          "NAME"));
}

}  // namespace ceilpose::ctl
