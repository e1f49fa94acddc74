#include "study/csv_table.hpp"

#include <cmath>
#include <fstream>
#include <sstream>

#include "core/packing_io.hpp"

namespace confpack::study {

namespace {

// The cells of one line; a quoted cell runs to its closing quote, "" inside it being one quote.
std::vector<std::string> splitLine(const std::string& line) {
  std::vector<std::string> cells(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c != '"')
        cells.back() += c;
      else if (i + 1 < line.size() && line[i + 1] == '"')
        cells.back() += line[++i];
      else
        quoted = false;
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      cells.emplace_back();
    } else if (c != '\r') {
      cells.back() += c;
    }
  }
  return cells;
}

std::string csvCell(const std::string& cell) {
  std::string out;
  bool quote = false;
  for (char c : cell) {
    if (c == '\n' || c == '\r') c = ' ';
    if (c == ',' || c == '"') quote = true;
    if (c == '"') out += '"';
    out += c;
  }
  return quote ? '"' + out + '"' : out;
}

void appendLine(std::string& out, const std::vector<std::string>& cells) {
  for (std::size_t i = 0; i < cells.size(); ++i) {
    if (i > 0) out += ',';
    out += csvCell(cells[i]);
  }
  out += '\n';
}

}  // namespace

std::optional<CsvTable> parseCsv(const std::string& text) {
  std::istringstream in(text);
  CsvTable t;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> cells = splitLine(line);
    if (t.columns.empty()) {
      t.columns = std::move(cells);
      continue;
    }
    if (cells.size() != t.columns.size()) continue;
    std::vector<double> row;
    for (const auto& c : cells) {
      try {
        row.push_back(std::stod(c));
      } catch (...) {
        row.push_back(std::nan(""));
      }
    }
    t.rows.push_back(std::move(row));
    t.text.push_back(std::move(cells));
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

std::string formatCsv(const std::vector<std::string>& columns, const std::vector<std::vector<std::string>>& rows) {
  std::string out;
  appendLine(out, columns);
  for (const auto& row : rows) appendLine(out, row);
  return out;
}

void writeCsv(const std::filesystem::path& path, const std::vector<std::string>& columns,
              const std::vector<std::vector<std::string>>& rows) {
  core::writeFileAtomically(path, formatCsv(columns, rows));
}

}  // namespace confpack::study
