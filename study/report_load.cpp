// The report's loading (study/report.hpp): the run table of a sweep folder, each run's status, marker
// and result.json flattened into its quantities, and each settled pile (RUN/settled/) as a record of its
// own.
#include <fstream>

#include "study/report.hpp"

namespace confpack::study {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// Deepest object nesting followed: a result.json that confpack writes is 4 levels deep
// (timing/phases/...); a hand-edited one 200,000 levels deep overflowed the stack (SIGSEGV).
constexpr int kMaxResultDepth = 16;

void flattenInto(const json& j, const std::string& path, std::map<std::string, std::optional<double>>& out,
                 int depth = 0) {
  if (j.is_object()) {
    if (depth == kMaxResultDepth) return;
    for (const auto& [key, v] : j.items()) {
      const std::string here = path.empty() ? key : path + "/" + key;
      if (here == "config" || here == "backend_settings" || here == "seed") continue;
      flattenInto(v, here, out, depth + 1);
    }
  } else if (j.is_number()) {
    out[path] = j.get<double>();
  } else if (j.is_boolean()) {
    out[path] = j.get<bool>() ? 1.0 : 0.0;
  } else if (j.is_null()) {
    out.try_emplace(path, std::nullopt);
  }
}

json readJson(const fs::path& path) {
  std::ifstream in(path);
  if (!in) return nullptr;
  try {
    return json::parse(in);
  } catch (const json::exception&) {
    return nullptr;
  }
}

}  // namespace

std::map<std::string, std::optional<double>> flattenResult(const json& result) {
  std::map<std::string, std::optional<double>> out;
  flattenInto(result, "", out);
  return out;
}

std::vector<RunRecord> loadStudy(const fs::path& sweepDir, SweepSpec* spec) {
  std::vector<RunRecord> out;
  for (SweepRun& r : readRunTable(sweepDir, spec)) {
    RunRecord rec;
    const fs::path dir = sweepDir / "runs" / r.name;
    rec.status = runStatus(dir);
    if (rec.status == RunStatus::Done) {
      rec.marker = readJson(dir / kDoneMarker);
      rec.result = readJson(dir / "result.json");
      if (rec.result.is_object()) {
        rec.values = flattenResult(rec.result);
      } else {
        // A done marker without a readable result: report the run as failed, with the reason.
        rec.status = RunStatus::Failed;
        rec.marker = {{"error", "done.json present but result.json missing or unreadable"}};
      }
    } else if (rec.status == RunStatus::Failed) {
      rec.marker = readJson(dir / kFailedMarker);
    }
    rec.run = std::move(r);
    out.push_back(std::move(rec));
  }
  // The settles after the table's runs, so that the backends keep their order and the settled
  // series comes third.
  const std::size_t tableRuns = out.size();
  for (std::size_t i = 0; i < tableRuns; ++i) {
    if (out[i].status != RunStatus::Done) continue;
    const fs::path dir = sweepDir / "runs" / out[i].run.name / kSettledFolder;
    json result = readJson(dir / "result.json");
    if (!result.is_object()) continue;
    RunRecord rec;
    rec.run = out[i].run;
    rec.run.name = (fs::path(out[i].run.name) / kSettledFolder).generic_string();
    rec.run.config.backend = settledName(out[i].run.config.backend);
    rec.status = RunStatus::Done;
    rec.settle = true;
    rec.marker = out[i].marker;
    rec.values = flattenResult(result);
    rec.result = std::move(result);
    out.push_back(std::move(rec));
  }
  return out;
}

std::string settledName(const std::string& backend) {
  return backend + "_settled";
}

}  // namespace confpack::study
