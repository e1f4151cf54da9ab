// The one table of exit codes, and the texts made from it or checked against it.
#include "core/exit_codes.h"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

namespace ceilpose {
namespace {

std::string service_doc() {
  std::ifstream in(std::string(CEILPOSE_SOURCE_DIR) + "/docs/service.md");
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The row of docs/service.md's exit-code table for `code`, or "".
std::string doc_row(const std::string& doc, int code) {
  const std::string start = "\n| " + std::to_string(code) + " | ";
  const size_t at = doc.find(start, doc.find("### Exit codes"));
  return at == std::string::npos ? "" : doc.substr(at + 1, doc.find('\n', at + 1) - at - 1);
}

TEST(ExitCodes, TheServiceDocumentsEveryCodeOfTheTable) {
  const std::string doc = service_doc();
  ASSERT_NE(doc.find("### Exit codes"), std::string::npos);
  for (const ExitCodeRow& row : exit_code_table()) {
    const std::string line = doc_row(doc, row.code);
    ASSERT_NE(line, "") << "docs/service.md has no row for exit code " << row.code;
    EXPECT_EQ(line.find("does not restart") != std::string::npos, row.restart_cannot_help)
        << "exit " << row.code
        << ": the table and docs/service.md disagree on the restart: " << line;
  }
}

TEST(ExitCodes, EachProgramsHelpListsItsCodesInOrder) {
  EXPECT_EQ(exit_codes_help(Program::kCeilposectl).find("Exit codes: 0 ok, 1 "), 0u);
  const std::string daemon = exit_codes_help(Program::kCeilposed);
  EXPECT_NE(daemon.find(", 3 bad configuration, 4 frame source failure, 5 shared-memory"),
            std::string::npos)
      << daemon;
  EXPECT_EQ(exit_codes_help(Program::kCeilposectl).find(", 5 "), std::string::npos)
      << "ceilposectl never exits 5";
}

TEST(ExitCodes, TheUnitStopsRetryingOnlyWhereRetryingCannotHelp) {
  EXPECT_EQ(restart_prevent_exit_status(), "3 5 6");
}

}  // namespace
}  // namespace ceilpose
