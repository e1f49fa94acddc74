#pragma once
// The one CSV code of confpack: it reads the profiles a run writes (analysis/analyze.hpp,
// writeResults), comma-separated, with '#' metadata lines and one header line naming the columns,
// and writes the report's tables (study/report.hpp), which it reads back the same way.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace confpack::study {

/// A table: column names and rows of values; a cell that is not a number is NaN in `rows` and
/// kept as written in `text` (the same cells, unquoted), so text columns can be read too.
struct CsvTable {
  std::vector<std::string> columns;
  std::vector<std::vector<double>> rows;
  std::vector<std::vector<std::string>> text;
};

/// Parses CSV text. Empty lines and lines starting with '#' are skipped; the first other line is
/// the header; rows whose cell count differs from the header's are dropped. A cell may be quoted
/// ("a,b", with "" for a quote) within its line. nullopt when there are fewer than two columns or
/// no row (not a profile).
std::optional<CsvTable> parseCsv(const std::string& text);

/// parseCsv of a file; nullopt also when the file cannot be read.
std::optional<CsvTable> readCsv(const std::filesystem::path& path);

/// CSV text of a header and rows of cells, one line each. A cell holding a comma or a double
/// quote is quoted; a line break in a cell becomes a space, as a row is one line to parseCsv.
std::string formatCsv(const std::vector<std::string>& columns, const std::vector<std::vector<std::string>>& rows);

/// formatCsv written to a file atomically (core::writeFileAtomically).
void writeCsv(const std::filesystem::path& path, const std::vector<std::string>& columns,
              const std::vector<std::vector<std::string>>& rows);

}  // namespace confpack::study
