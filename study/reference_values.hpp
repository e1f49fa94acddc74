#pragma once
// Published values a user compares a study with (docs/reference-values.md): per family (MSP, BSP,
// MPP, BPP, as the report names them; an entry may be narrowed to one x_S and one mu_w) the
// summary's quantities phi_bulk, C, Z_bulk, C_Z and lambda_L/d_avg, each with its uncertainty and
// the citation it comes from. confpack ships no such values of its own: `confpack report
// --reference FILE` reads the user's file and shows it next to the study's numbers in the summary
// and as marks on the phi(W) and Z(W) figures.
//
// The reader is strict, as every input of the toolkit: an unknown key, family or quantity, a
// missing value, uncertainty or citation, a number out of range, is refused with one message that
// names the file and the field ("ref.json: families.MSP.phi_bulk.uncertainty: must be >= 0 (got
// -0.1)").
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace confpack::study {

/// Value of the "format" key of a reference file.
inline constexpr std::string_view kReferenceFormat = "confpack-reference";
inline constexpr int kReferenceVersion = 1;

/// One published number.
struct ReferenceValue {
  double value = 0.0;        ///< in the quantity's unit (C and C_Z in d_L, the others dimensionless)
  double uncertainty = 0.0;  ///< as published (a standard error where the source gives one), >= 0
  std::string citation;      ///< where it comes from, printed as given
};

/// A quantity a reference file may give: its key in the file and its name in the report.
struct ReferenceQuantity {
  std::string key;   ///< "lambda_L_over_d_avg"
  std::string name;  ///< "lambda_L/d_avg", as the summary's column
};

/// phi_bulk, C, Z_bulk, C_Z, lambda_L_over_d_avg, in the summary's order.
const std::vector<ReferenceQuantity>& referenceQuantities();

/// The families a reference file is keyed by, as the report names them (study/sweep.hpp,
/// familyName): MSP, BSP, MPP, BPP.
const std::vector<std::string>& referenceFamilies();

struct ReferenceEntry {
  std::string family;                            ///< MSP, BSP, MPP or BPP
  std::optional<double> smallFraction;           ///< x_S [%]; absent: every x_S of the family
  std::optional<double> wallFriction;            ///< mu_w [-]; absent: every mu_w
  std::map<std::string, ReferenceValue> values;  ///< by quantity key
  std::string where;                             ///< "families.BSP[1]", for messages
};

struct ReferenceValues {
  std::string source;       ///< the file, as the report names it
  std::string description;  ///< free text of the file ("" when absent)
  std::vector<ReferenceEntry> entries;

  /// The value of quantity `key` for the series (family, x_S, mu_w): from the most specific entry
  /// that matches and gives it (x_S and mu_w both given, then x_S alone, then mu_w alone, then
  /// neither); nullptr when no entry does.
  const ReferenceValue* find(std::string_view family, double smallFraction, double wallFriction,
                             std::string_view key) const;
};

/// Validates a reference document; throws std::invalid_argument "SOURCE: FIELD: what".
ReferenceValues parseReferenceValues(const nlohmann::json& doc, std::string_view source);
/// Reads and parses a reference file (JSON).
ReferenceValues readReferenceValues(const std::filesystem::path& path);

}  // namespace confpack::study
