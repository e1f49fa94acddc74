#include "compaction/checkpoint.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <new>
#include <stdexcept>

#include "core/json_input.hpp"
#include "core/packing_io.hpp"

namespace confpack::compaction {

namespace {

constexpr std::string_view kFormat = "confpack-checkpoint";
constexpr int kVersion = 1;

/// FNV-1a over the bits of the grains' poses and sizes (a fingerprint, not a cryptographic hash:
/// it tells a checkpoint of another deposit from this one's).
std::string depositFingerprint(const Deposit& deposit) {
  std::uint64_t h = 14695981039346656037ull;
  const auto add = [&](double x) {
    std::uint64_t bits;
    std::memcpy(&bits, &x, sizeof bits);
    for (int k = 0; k < 8; ++k) {
      h ^= (bits >> (8 * k)) & 0xffu;
      h *= 1099511628211ull;
    }
  };
  for (const core::Grain& g : deposit.grains) {
    for (int k = 0; k < 3; ++k) add(g.position[k]);
    for (int k = 0; k < 4; ++k) add(g.orientation.coeffs()[k]);
    add(g.volume());
    add(g.boundingRadius());
  }
  return fmt::format("{:016x}", h);
}

/// JSON has no infinity (nlohmann writes null): the first checks' ratios are infinite.
nlohmann::json number(double x) {
  if (std::isfinite(x)) return x;
  return std::isnan(x) ? "nan" : x > 0.0 ? "inf" : "-inf";
}

double numberFrom(const nlohmann::json& j) {
  if (j.is_string()) {
    const std::string s = j.get<std::string>();
    if (s == "inf") return std::numeric_limits<double>::infinity();
    if (s == "-inf") return -std::numeric_limits<double>::infinity();
    if (s == "nan") return std::numeric_limits<double>::quiet_NaN();
  }
  return j.get<double>();
}

nlohmann::json historyToJson(const std::vector<CheckPoint>& history) {
  nlohmann::json out = nlohmann::json::array();
  for (const CheckPoint& c : history)
    out.push_back({c.steps, c.time, c.wallSeconds, number(c.maxForceRatio), number(c.maxMomentRatio),
                   number(c.maxKineticRatio), number(c.interpenetrationPercent), c.iterations, c.rowUpdates,
                   c.solveSeconds, c.stepSeconds, c.stepCpuSeconds, number(c.solidFraction), number(c.coordination)});
  return out;
}

std::vector<CheckPoint> historyFromJson(const nlohmann::json& j) {
  std::vector<CheckPoint> out;
  for (const nlohmann::json& e : j) {
    // 12 numbers: a checkpoint from before the relaxation history had phi and Z.
    if (!e.is_array() || (e.size() != 12 && e.size() != 14))
      throw std::invalid_argument("a history entry is not 14 numbers");
    const double nan = std::numeric_limits<double>::quiet_NaN();
    out.push_back({e[0].get<long>(), e[1].get<double>(), e[2].get<double>(), numberFrom(e[3]), numberFrom(e[4]),
                   numberFrom(e[5]), numberFrom(e[6]), e[7].get<long>(), e[8].get<double>(), e[9].get<double>(),
                   e[10].get<double>(), e[11].get<double>(), e.size() == 14 ? numberFrom(e[12]) : nan,
                   e.size() == 14 ? numberFrom(e[13]) : nan});
  }
  return out;
}

}  // namespace

nlohmann::json checkpointIdentity(const core::RunConfig& cfg, const Deposit& deposit) {
  nlohmann::json config = cfg;
  config.erase("threads");
  return {{"config", std::move(config)},
          {"grains", deposit.grains.size()},
          {"deposit_fingerprint", depositFingerprint(deposit)}};
}

void writeCheckpoint(const std::filesystem::path& file, const nlohmann::json& identity, const CompactionCounters& c,
                     const nlohmann::json& backend, const nlohmann::json& finisher) {
  nlohmann::json j = {{"format", kFormat},
                      {"version", kVersion},
                      {"identity", identity},
                      {"stage", c.finisherStage ? "finisher" : "fall"},
                      {"steps", c.steps},
                      {"sim_time", c.simTime},
                      {"dt", c.dt},
                      {"dt_largest", c.dtLargest},
                      {"last_check_time", c.lastCheckTime},
                      {"iterations", c.iterations},
                      {"row_updates", c.rowUpdates},
                      {"step_s", c.stepSeconds},
                      {"step_cpu_s", c.stepCpuSeconds},
                      {"elapsed_s", c.elapsedSeconds},
                      {"phase_s", c.phaseSeconds},
                      {"history", historyToJson(c.history)},
                      {"resumes", c.resumes},
                      {"backend", backend}};
  if (c.finisherStage) {
    j["hand_over"] = {{"at", c.handOverAt},
                      {"kinetic_ratio", c.handOverKineticRatio},
                      {"dynamic_steps", c.dynamicSteps},
                      {"dynamic_iterations", c.dynamicIterations},
                      {"dynamic_wall_s", c.dynamicWallSeconds}};
    j["finisher"] = finisher;
  }
  if (file.has_parent_path()) std::filesystem::create_directories(file.parent_path());
  core::writeFileAtomically(file, j.dump());
}

std::optional<LoadedCheckpoint> readCheckpoint(const std::filesystem::path& file, const nlohmann::json& identity,
                                               std::string& why) {
  why.clear();
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) return std::nullopt;
  try {
    const nlohmann::json j = core::readJsonFile(file, "checkpoint");
    if (j.value("format", "") != kFormat || j.value("version", 0) != kVersion)
      throw std::runtime_error(fmt::format("not a {} file of version {}", kFormat, kVersion));
    if (j.at("identity") != identity) {
      why = "it is another run's (its configuration or deposit differ)";
      return std::nullopt;
    }
    LoadedCheckpoint out;
    CompactionCounters& c = out.counters;
    const std::string stage = j.at("stage").get<std::string>();
    if (stage != "fall" && stage != "finisher") throw std::runtime_error("unknown stage");
    c.finisherStage = stage == "finisher";
    c.steps = j.at("steps").get<long>();
    c.simTime = j.at("sim_time").get<double>();
    c.dt = j.at("dt").get<double>();
    c.dtLargest = j.at("dt_largest").get<double>();
    c.lastCheckTime = j.at("last_check_time").get<double>();
    c.iterations = j.at("iterations").get<long>();
    c.rowUpdates = j.at("row_updates").get<double>();
    c.stepSeconds = j.at("step_s").get<double>();
    c.stepCpuSeconds = j.at("step_cpu_s").get<double>();
    c.elapsedSeconds = j.at("elapsed_s").get<double>();
    c.phaseSeconds = j.at("phase_s").get<decltype(c.phaseSeconds)>();
    c.history = historyFromJson(j.at("history"));
    c.resumes = j.at("resumes").get<int>();
    if (c.steps < 0 || !(c.dt > 0.0) || c.resumes < 0) throw std::runtime_error("counters out of range");
    out.backend = j.at("backend");
    if (c.finisherStage) {
      const nlohmann::json& h = j.at("hand_over");
      c.handOverAt = h.at("at").get<std::string>();
      c.handOverKineticRatio = h.at("kinetic_ratio").get<double>();
      c.dynamicSteps = h.at("dynamic_steps").get<long>();
      c.dynamicIterations = h.at("dynamic_iterations").get<long>();
      c.dynamicWallSeconds = h.at("dynamic_wall_s").get<double>();
      out.finisher = j.at("finisher");
    }
    return out;
  } catch (const std::bad_alloc&) {
    throw;  // out of memory is the run's failure, not a damaged file
  } catch (const std::exception& e) {
    why = fmt::format("it cannot be read ({})", e.what());
    return std::nullopt;
  }
}

std::string describeCheckpoint(const std::filesystem::path& file) {
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) return {};
  try {
    const nlohmann::json j = core::readJsonFile(file, "checkpoint");
    const double minutes = j.at("elapsed_s").get<double>() / 60.0;
    const double t = j.at("sim_time").get<double>();
    std::string where = j.at("stage") == "finisher"
                            ? fmt::format("checkpoint: finisher step {} (t = {:.1f}), {:.0f} min",
                                          j.at("finisher").at("steps").get<long>(), t, minutes)
                            : fmt::format("checkpoint: fall at t = {:.1f}, {:.0f} min", t, minutes);
    // How far from rest: the last check that measured the ratios (the first checks of a fall have
    // no contacts to measure), against the run's bounds.
    const std::vector<CheckPoint> history = historyFromJson(j.at("history"));
    const auto measured = std::find_if(history.rbegin(), history.rend(), [](const CheckPoint& c) {
      return std::isfinite(c.maxForceRatio) && std::isfinite(c.maxKineticRatio);
    });
    if (measured != history.rend()) {
      const nlohmann::json& bounds = j.at("identity").at("config").at("compaction");
      where += fmt::format("; last check: force ratio {:.2g} (rest below {:.2g}), kinetic ratio {:.2g} (below {:.2g})",
                           measured->maxForceRatio, bounds.at("force_ratio").get<double>(), measured->maxKineticRatio,
                           bounds.at("kinetic_ratio").get<double>());
    }
    return where;
  } catch (const std::exception&) {
    return {};
  }
}

}  // namespace confpack::compaction
