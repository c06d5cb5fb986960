#pragma once
// results.csv as the tests read it back: one row per value, fields unquoted.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

namespace plydem::test {

// The rows of a results.csv (experiment, case, quantity, source, value, unit), each field with
// its CSV quotes removed; checks the header and that every row has six fields.
inline std::vector<std::vector<std::string>> results_csv_rows(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::string line;
  REQUIRE(std::getline(in, line));
  CHECK(line == "experiment,case,quantity,source,value,unit");
  std::vector<std::vector<std::string>> rows;
  while (std::getline(in, line)) {
    std::vector<std::string> fields;
    std::string field;
    bool quoted = false;
    for (char ch : line) {
      if (ch == '"')
        quoted = !quoted;
      else if (ch == ',' && !quoted)
        fields.push_back(std::exchange(field, ""));
      else
        field += ch;
    }
    fields.push_back(field);
    REQUIRE(fields.size() == 6);
    rows.push_back(std::move(fields));
  }
  return rows;
}

}  // namespace plydem::test
