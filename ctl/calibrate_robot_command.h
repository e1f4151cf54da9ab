#pragma once
// `calibrate robot`, a sub-command of `calibrate` (calibrate_command.cpp).
#include <CLI/CLI.hpp>

namespace ceilpose::ctl {

void add_calibrate_robot_command(CLI::App* calibrate);

}  // namespace ceilpose::ctl
