#pragma once
// The one CSV reader of confpack: the profiles a run writes (analysis/analyze.hpp, writeResults),
// comma-separated, with '#' metadata lines and one header line naming the columns.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace confpack::study {

/// A numeric table: column names and rows of values; a cell that is not a number is NaN.
struct CsvTable {
  std::vector<std::string> columns;
  std::vector<std::vector<double>> rows;
};

/// Parses CSV text. Empty lines and lines starting with '#' are skipped; the first other line is
/// the header; rows whose cell count differs from the header's are dropped. nullopt when there
/// are fewer than two columns or no row (not a profile).
std::optional<CsvTable> parseCsv(const std::string& text);

/// parseCsv of a file; nullopt also when the file cannot be read.
std::optional<CsvTable> readCsv(const std::filesystem::path& path);

}  // namespace confpack::study
