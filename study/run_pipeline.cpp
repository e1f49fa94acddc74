#include "study/run_pipeline.hpp"

#include <fmt/format.h>

#include <array>
#include <stdexcept>
#include <string_view>

#include "analysis/bulk_region.hpp"
#include "analysis/coordination.hpp"
#include "analysis/displacement.hpp"
#include "analysis/solid_fraction.hpp"
#include "core/build_info.hpp"
#include "core/json_input.hpp"
#include "core/packing_io.hpp"

namespace confpack::study {

analysis::AnalysisOptions analysisOptions() {
  analysis::AnalysisOptions o;
  o.equilibrium = false;  // the pipeline has the velocities: it writes its own block
  return o;
}

void checkRunCells(const core::RunConfig& cfg, double grains) {
  analysis::checkCells(cfg.box, grains, analysisOptions(),
                       "a run analyses with the default slices and cells: make the box smaller");
}

namespace {
// The metadata lines of a run's profiles (analysis::writeProfiles).
nlohmann::json profileMetadata(const nlohmann::json& seed, const std::string& backend) {
  return {{"seed", seed}, {"backend", backend}, {"version", core::version()}, {"revision", core::sourceRevision()}};
}

// The keys of result.json that makeResult writes beside the analysis blocks: the compaction's.
constexpr std::array<std::string_view, 10> kCompactionKeys = {
    "backend", "seed",   "n_grains",         "equilibrium",       "timing",
    "deposit", "config", "confpack_version", "confpack_revision", "settle"};

// The measurements a settle record compares before and after, as the analysis measures them:
// phi of the bulk, Z by type (null without a bulk region, or without a grain in it).
nlohmann::json settleSide(const core::Packing& p) {
  const analysis::BulkRegion region = analysis::bulkRegion(p);
  if (region.empty())
    return {{"solid_fraction", nullptr}, {"Z", nullptr},      {"simple", nullptr},
            {"double", nullptr},         {"triple", nullptr}, {"wall", nullptr}};
  const analysis::Coordination c = analysis::bulkCoordination(p, region);
  const auto perGrain = [&](double v) { return c.bulkGrains > 0 ? nlohmann::json(v) : nlohmann::json(nullptr); };
  return {{"solid_fraction", analysis::solidFraction(p, region).phi},
          {"Z", perGrain(c.z)},
          {"simple", perGrain(c.zSimple)},
          {"double", perGrain(c.zDouble)},
          {"triple", perGrain(c.zTriple)},
          {"wall", perGrain(c.wallZ)}};
}
}  // namespace

nlohmann::json settleRecord(const core::RunConfig& cfg, const compaction::Deposit& from,
                            const compaction::CompactionOutcome& out) {
  const analysis::Displacement moved = analysis::displacement(cfg.box, from.grains, out.packing.grains);
  return {{"from", from.source},
          {"reached", out.reached},
          {"steps", out.timing.value("steps", 0L)},
          {"simulated_time", out.equilibrium.value("simulated_time", 0.0)},
          {"max_displacement", moved.max},
          {"mean_displacement", moved.mean},
          {"max_displacement_grain", moved.maxGrain},
          {"before", settleSide(core::Packing{cfg.box, cfg.walls, from.grains, from.contacts})},
          {"after", settleSide(out.packing)}};
}

nlohmann::json makeResult(const core::RunConfig& cfg, const compaction::Deposit& deposit,
                          const compaction::CompactionOutcome& out, const analysis::Analysis& measured) {
  nlohmann::json r = analysis::toJson(measured);
  // Every key set here is one of kCompactionKeys, which reanalyseRun keeps.
  r["backend"] = cfg.backend;
  r["seed"] = cfg.seed;
  r["n_grains"] = out.packing.grains.size();
  r["equilibrium"] = out.equilibrium;
  r["timing"] = out.timing;
  r["timing"]["deposit_s"] = deposit.seconds;
  r["timing"]["wall_s"] = out.timing["compaction_s"].get<double>() + deposit.seconds;
  r["deposit"] = {{"pile_height", deposit.pileHeight},
                  {"placeholder_diameter", deposit.placeholderDiameter},
                  {"solid_fraction", deposit.solidFraction}};
  if (!deposit.source.empty()) r["deposit"]["from"] = deposit.source;
  r["config"] = cfg;
  r["config"]["backend_settings"] = out.backendSettings;
  r["config"]["compaction"]["dt"] = out.dt;
  r["confpack_version"] = core::version();
  r["confpack_revision"] = core::sourceRevision();
  return r;
}

Reanalysed reanalyseRun(const std::filesystem::path& runDir) {
  const std::filesystem::path resultFile = runDir / "result.json";
  Reanalysed r{core::readJsonFile(resultFile, "result file"), nlohmann::json()};
  if (!r.before.is_object()) throw std::invalid_argument(fmt::format("{}: not a JSON object", resultFile.string()));
  const analysis::Analysis measured = analysis::analyze(core::readPacking(runDir / "packing.json"), analysisOptions());
  r.after = analysis::toJson(measured);
  for (std::string_view key : kCompactionKeys)
    if (r.before.contains(key)) r.after[std::string(key)] = r.before[std::string(key)];
  analysis::writeProfiles(runDir, measured,
                          profileMetadata(r.before.value("seed", nlohmann::json()), r.before.value("backend", "")));
  core::writeFileAtomically(resultFile, r.after.dump(2));
  return r;
}

FinishedRun runProtocol(const core::RunConfig& cfg, const std::filesystem::path& vtkDir, const RunProgressFn& progress,
                        const compaction::Deposit* shared, const compaction::Checkpointing& checkpointing) {
  const compaction::Deposit dep =
      shared ? *shared : compaction::deposit(cfg.box, cfg.population, cfg.deposition, cfg.seed);
  compaction::CompactionOutcome out = compaction::compact(cfg, dep, vtkDir, progress, checkpointing);
  analysis::Analysis measured = analysis::analyze(out.packing, analysisOptions());
  nlohmann::json result = makeResult(cfg, dep, out, measured);
  // A run from a packing (`run --from`) records what it did to that packing.
  if (!dep.source.empty()) result["settle"] = settleRecord(cfg, dep, out);
  return {std::move(out.packing), std::move(measured), std::move(result)};
}

nlohmann::json runAndWrite(const core::RunConfig& cfg, const std::filesystem::path& outDir,
                           const RunProgressFn& progress, const compaction::Deposit* shared,
                           const compaction::Checkpointing& checkpointing) {
  const FinishedRun run = runProtocol(cfg, outDir / "vtk", progress, shared, checkpointing);
  core::writePacking(run.packing, outDir / "packing.json");
  analysis::writeProfiles(outDir, run.measured, profileMetadata(cfg.seed, cfg.backend));
  core::writeFileAtomically(outDir / "result.json", run.result.dump(2));
  if (!checkpointing.file.empty()) {
    std::error_code ignored;  // a checkpoint left behind is ignored once the run is done
    std::filesystem::remove(checkpointing.file, ignored);
  }
  return run.result;
}

core::RunConfig settleConfig(const core::RunConfig& cfg, const std::string& backend) {
  core::RunConfig c = cfg;
  c.backend = backend;
  c.backendOptions = nlohmann::json::object();  // the run's options are its own backend's
  c.compaction.protocol = core::Protocol::QuasiStatic;
  return c;
}

nlohmann::json settleAndWrite(const core::RunConfig& cfg, const std::filesystem::path& runDir,
                              const std::string& backend, const RunProgressFn& progress,
                              const compaction::Checkpointing& checkpointing) {
  const compaction::Deposit from = compaction::depositFromPacking(core::readPacking(runDir / "packing.json"),
                                                                  std::filesystem::path("..") / "packing.json");
  const core::RunConfig settling = settleConfig(cfg, backend);
  const std::filesystem::path outDir = runDir / kSettledFolder;
  std::filesystem::create_directories(outDir);
  core::writeFileAtomically(outDir / "config.json", nlohmann::json(settling).dump(2));
  return runAndWrite(settling, outDir, progress, &from, checkpointing);
}

}  // namespace confpack::study
