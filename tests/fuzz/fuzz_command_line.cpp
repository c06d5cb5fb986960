#include <stdexcept>
#include <string>
#include <vector>

#include "experiments/cli/command_line.hpp"
#include "tests/fuzz/fuzz_inputs.hpp"

namespace plydem::fuzz {

void command_line(std::string_view input) {
  std::vector<std::string> arguments{"plydem"};
  std::string current;
  for (char c : input) {
    if (c == '\n' || c == '\0') {
      arguments.push_back(current);
      current.clear();
    } else {
      current += c;
    }
  }
  if (!current.empty()) arguments.push_back(current);
  std::vector<char*> argv;
  for (std::string& a : arguments) argv.push_back(a.data());
  argv.push_back(nullptr);
  // Errors are printed and returned as exit codes, as the command line does: 0, 2 (plydem::Error)
  // and CLI11's parse-error codes are answers; 3, an exception that is no plydem::Error, is a bug.
  const int rc = plydem_command_line(static_cast<int>(arguments.size()), argv.data(), true);
  if (rc == 3) throw std::logic_error("plydem_command_line: internal error (exit 3)");
}

}  // namespace plydem::fuzz
