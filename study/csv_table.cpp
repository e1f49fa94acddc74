#include "study/csv_table.hpp"

#include <cmath>
#include <fstream>
#include <sstream>

namespace confpack::study {

std::optional<CsvTable> parseCsv(const std::string& text) {
  std::istringstream in(text);
  CsvTable t;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> cells;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) cells.push_back(cell);
    if (t.columns.empty()) {
      t.columns = cells;
      continue;
    }
    std::vector<double> row;
    for (const auto& c : cells) {
      try {
        row.push_back(std::stod(c));
      } catch (...) {
        row.push_back(std::nan(""));
      }
    }
    if (row.size() == t.columns.size()) t.rows.push_back(std::move(row));
  }
  if (t.columns.size() < 2 || t.rows.empty()) return std::nullopt;
  return t;
}

std::optional<CsvTable> readCsv(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) return std::nullopt;
  std::ostringstream text;
  text << in.rdbuf();
  return parseCsv(text.str());
}

}  // namespace confpack::study
