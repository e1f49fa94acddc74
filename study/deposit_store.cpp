#include "study/deposit_store.hpp"

#include <fmt/format.h>

#include <fstream>
#include <stdexcept>

#include "core/packing_io.hpp"

namespace confpack::study {

namespace {

constexpr std::string_view kDepositFormat = "confpack-deposit";
constexpr int kDepositVersion = 1;

double number(const nlohmann::json& j, const char* key, std::string_view source) {
  if (!j.contains(key) || !j.at(key).is_number())
    throw std::invalid_argument(fmt::format("{}: {}: missing or not a number", source, key));
  return j.at(key).get<double>();
}

}  // namespace

nlohmann::json depositToJson(const compaction::Deposit& deposit, const core::BoxDef& box) {
  core::Packing packing;
  packing.box = box;
  packing.grains = deposit.grains;
  nlohmann::json placeholders = nlohmann::json::array();
  for (const core::Vec3& p : deposit.placeholders) placeholders.push_back({p.x(), p.y(), p.z()});
  return {{"format", kDepositFormat},
          {"version", kDepositVersion},
          {"packing", core::toJson(packing)},
          {"placeholders", std::move(placeholders)},
          {"placeholder_diameter", deposit.placeholderDiameter},
          {"pile_height", deposit.pileHeight},
          {"placeholder_solid_fraction", deposit.placeholderSolidFraction},
          {"solid_fraction", deposit.solidFraction},
          {"seconds", deposit.seconds}};
}

compaction::Deposit depositFromJson(const nlohmann::json& j, std::string_view source) {
  if (!j.is_object() || j.value("format", std::string()) != kDepositFormat)
    throw std::invalid_argument(fmt::format("{}: format: not a {} document", source, kDepositFormat));
  if (j.value("version", 0) != kDepositVersion)
    throw std::invalid_argument(fmt::format("{}: version: expected {}", source, kDepositVersion));
  if (!j.contains("packing")) throw std::invalid_argument(fmt::format("{}: packing: missing", source));
  compaction::Deposit d;
  d.grains = core::packingFromJson(j.at("packing"), fmt::format("{}: packing", source)).grains;
  const nlohmann::json& ph = j.value("placeholders", nlohmann::json::array());
  if (!ph.is_array() || ph.size() != d.grains.size())
    throw std::invalid_argument(
        fmt::format("{}: placeholders: expected {} points, one per grain", source, d.grains.size()));
  d.placeholders.reserve(ph.size());
  for (std::size_t i = 0; i < ph.size(); ++i) {
    const nlohmann::json& p = ph[i];
    if (!p.is_array() || p.size() != 3 || !p[0].is_number() || !p[1].is_number() || !p[2].is_number())
      throw std::invalid_argument(fmt::format("{}: placeholders[{}]: expected [x, y, z]", source, i));
    d.placeholders.emplace_back(p[0].get<double>(), p[1].get<double>(), p[2].get<double>());
  }
  d.placeholderDiameter = number(j, "placeholder_diameter", source);
  d.pileHeight = number(j, "pile_height", source);
  d.placeholderSolidFraction = number(j, "placeholder_solid_fraction", source);
  d.solidFraction = number(j, "solid_fraction", source);
  d.seconds = number(j, "seconds", source);
  return d;
}

void writeDeposit(const compaction::Deposit& deposit, const core::BoxDef& box, const std::filesystem::path& path) {
  core::writeFileAtomically(path, depositToJson(deposit, box).dump());
}

compaction::Deposit readDeposit(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument(fmt::format("{}: cannot open", path.string()));
  nlohmann::json j;
  try {
    in >> j;
  } catch (const nlohmann::json::exception& e) {
    throw std::invalid_argument(fmt::format("{}: not valid JSON ({})", path.string(), e.what()));
  }
  return depositFromJson(j, path.string());
}

}  // namespace confpack::study
