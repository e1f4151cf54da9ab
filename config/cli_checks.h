#pragma once
// Command-line checks ceilposed and ceilposectl share (header-only over
// CLI11): values a launch script gets wrong by accident must be usage
// errors, never a default taken in their place or a run that never ends.
#include <CLI/CLI.hpp>
#include <cmath>
#include <exception>
#include <string>

namespace ceilpose::cli {

// `--source "$CAM"` with CAM unset must not mean "the default": on a robot
// that would be the simulator's poses published as real ones.
inline CLI::Validator not_empty() {
  return CLI::Validator(
      [](const std::string& value) {
        return value.empty()
                   ? std::string("must not be empty (an unset variable in a launch script?)")
                   : std::string();
      },
      "NOT EMPTY");
}

// `value` read whole as a number (nan and inf included); false when it is
// not one.
inline bool whole_number(const std::string& value, double* out) {
  try {
    size_t used = 0;
    *out = std::stod(value, &used);
    return used == value.size();
  } catch (const std::exception&) {
    return false;
  }
}

// A finite number of seconds above 0: nan, inf or 0 would never stop.
inline CLI::Validator positive_seconds() {
  return CLI::Validator(
      [](const std::string& value) {
        double s = 0.0;
        return whole_number(value, &s) && std::isfinite(s) && s > 0.0
                   ? std::string()
                   : "must be a number of seconds above 0, got '" + value + "'";
      },
      "SECONDS > 0");
}

// A whole number of at least 0 (a count where 0 has a documented meaning).
inline CLI::Validator count() {
  return CLI::Validator(
      [](const std::string& value) {
        const bool digits =
            !value.empty() && value.find_first_not_of("0123456789") == std::string::npos;
        return digits ? std::string() : "must be a whole number of at least 0, got '" + value + "'";
      },
      "N >= 0");
}

// A finite number: CLI11's Range and PositiveNumber compare, and NaN passes
// every comparison.
inline CLI::Validator finite_number() {
  return CLI::Validator(
      [](const std::string& value) {
        double v = 0.0;
        // Not a number at all: CLI11's own conversion says so.
        return !whole_number(value, &v) || std::isfinite(v)
                   ? std::string()
                   : "must be a finite number, got '" + value + "'";
      },
      "FINITE");
}

// Every floating-point option of `app` and of its sub-commands refuses nan
// and inf (a usage error, exit 2), so no option can forget it. Call after
// every option is added.
inline void refuse_non_finite_numbers(CLI::App& app) {
  for (CLI::Option* option : app.get_options())
    if (option->get_type_name().rfind("FLOAT", 0) == 0) option->check(finite_number());
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; }))
    refuse_non_finite_numbers(*sub);
}

}  // namespace ceilpose::cli
