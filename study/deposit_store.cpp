#include "study/deposit_store.hpp"

#include <fmt/format.h>

#include "core/input_document.hpp"
#include "core/json_input.hpp"
#include "core/packing_io.hpp"

namespace confpack::study {

namespace {

constexpr std::string_view kDepositFormat = "confpack-deposit";
constexpr int kDepositVersion = 1;

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
  const core::ObjectReader r =
      core::readDocument(j, source, {kDepositFormat, kDepositVersion},
                         {"format", "version", "packing", "placeholders", "placeholder_diameter", "pile_height",
                          "placeholder_solid_fraction", "solid_fraction", "seconds"});
  compaction::Deposit d;
  d.grains = core::packingFromJson(r.at("packing"), fmt::format("{}: packing", source)).grains;
  const nlohmann::json& ph = r.array("placeholders");
  if (ph.size() != d.grains.size())
    r.refuse("placeholders", fmt::format("expected {} points, one per grain (got {})", d.grains.size(), ph.size()));
  d.placeholders.reserve(ph.size());
  for (std::size_t i = 0; i < ph.size(); ++i) {
    const nlohmann::json& p = ph[i];
    const std::string field = fmt::format("placeholders[{}]", i);
    if (!p.is_array() || p.size() != 3) r.refuse(field, "expected [x, y, z]");
    d.placeholders.emplace_back(r.toNumber(p[0], field), r.toNumber(p[1], field), r.toNumber(p[2], field));
  }
  d.placeholderDiameter = r.number("placeholder_diameter");
  d.pileHeight = r.number("pile_height");
  d.placeholderSolidFraction = r.number("placeholder_solid_fraction");
  d.solidFraction = r.number("solid_fraction");
  d.seconds = r.number("seconds");
  return d;
}

void writeDeposit(const compaction::Deposit& deposit, const core::BoxDef& box, const std::filesystem::path& path) {
  core::writeFileAtomically(path, depositToJson(deposit, box).dump());
}

compaction::Deposit readDeposit(const std::filesystem::path& path) {
  return depositFromJson(core::readJsonFile(path, "deposit"), path.string());
}

}  // namespace confpack::study
