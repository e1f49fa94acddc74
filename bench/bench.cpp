#include "bench/bench.hpp"

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <thread>

#include "analysis/bulk_region.hpp"
#include "analysis/interpenetration.hpp"
#include "compaction/deposition.hpp"
#include "compaction/time_step.hpp"
#include "core/build_info.hpp"
#include "study/run_pipeline.hpp"

namespace confpack::bench {

namespace {

/// Peak resident memory of this process [MiB] (VmHWM of /proc/self/status).
double peakRssMb() {
  std::ifstream in("/proc/self/status");
  std::string key;
  while (in >> key) {
    if (key == "VmHWM:") {
      double kb = 0.0;
      in >> kb;
      return kb / 1024.0;
    }
    std::string rest;
    std::getline(in, rest);
  }
  return 0.0;
}

/// Resets VmHWM to the current RSS (Linux >= 4.0), so each backend's peak is its own.
void resetPeakRss() {
  std::ofstream out("/proc/self/clear_refs");
  out << "5";
}

nlohmann::json machineInfo() {
  std::string model;
  std::ifstream cpu("/proc/cpuinfo");
  for (std::string line; std::getline(cpu, line);)
    if (line.rfind("model name", 0) == 0) {
      model = line.substr(line.find(':') + 2);
      break;
    }
  // The kernel's transparent huge page mode (the bracketed word) and glibc's tunables: with
  // "madvise", GLIBC_TUNABLES=glibc.malloc.hugetlb=1 puts the solver's arrays on 2 MiB pages,
  // which may change the cost of an iteration at 30,000 grains (about 5% in a micro-benchmark,
  // docs/performance.md).
  std::string thp;
  std::ifstream thpIn("/sys/kernel/mm/transparent_hugepage/enabled");
  if (std::getline(thpIn, thp)) {
    const auto open = thp.find('['), close = thp.find(']');
    if (open != std::string::npos && close != std::string::npos && close > open)
      thp = thp.substr(open + 1, close - open - 1);
  }
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  return {{"cpu", model},
          {"hardware_threads", std::thread::hardware_concurrency()},
          {"compiler", __VERSION__},
          {"confpack_version", core::version()},
          {"confpack_revision", core::sourceRevision()},
          {"transparent_hugepage", thp.empty() ? nlohmann::json() : nlohmann::json(thp)},
          {"glibc_tunables", tunables ? nlohmann::json(tunables) : nlohmann::json()}};
}

core::RunConfig baseConfig(const BenchDef& def, core::ShapeKind shape) {
  core::RunConfig cfg;
  cfg.population.shape = shape;
  cfg.box.lengthX = 20.0 * def.scale;
  cfg.box.width = 10.0 * def.scale;
  cfg.box.height = 16.0;
  cfg.seed = def.seed;
  cfg.threads = def.threads;
  cfg.compaction.timeLimit = def.timeLimit;
  cfg.compaction.adaptiveDt = def.adaptiveDt;
  cfg.compaction.protocol = def.protocol;
  return cfg;
}

struct BackendRun {
  nlohmann::json json;
  double finalInterpenetration = 0.0;
  compaction::CompactionOutcome outcome;
};

/// `progress` with every status led by `what` (the case: a compaction's own status starts with
/// its backend).
study::RunProgressFn labelled(const study::RunProgressFn& progress, std::string what) {
  if (!progress) return {};
  return [progress, what = std::move(what)](double fraction, const std::string& status) {
    progress(fraction, what + " " + status);
  };
}

BackendRun runBackend(core::RunConfig cfg, const std::string& backend, const compaction::Deposit& dep,
                      const study::RunProgressFn& progress) {
  cfg.backend = backend;
  resetPeakRss();
  BackendRun run;
  run.outcome = compaction::compact(cfg, dep, {}, progress);
  const compaction::CompactionOutcome& out = run.outcome;
  const analysis::Interpenetration inter =
      analysis::interpenetration(out.packing, analysis::bulkRegion(out.packing), analysis::InterpenetrationDef{});
  run.finalInterpenetration = inter.exactPercent;
  const double wall = out.timing["compaction_s"].get<double>();
  const long steps = out.timing["steps"].get<long>();
  nlohmann::json phases = nlohmann::json::object();
  for (const auto& [name, seconds] : out.timing["phases"].items())
    phases[name] = steps > 0 ? seconds.get<double>() / steps : 0.0;  // per step
  run.json = {{"time_to_equilibrium_s", out.reached ? nlohmann::json(wall) : nlohmann::json(nullptr)},
              {"wall_s", wall},
              {"equilibrium_reached", out.reached},
              {"protocol", out.timing["protocol"]},
              {"stages", out.timing["stages"]},
              {"equilibrium", out.equilibrium},
              {"interpenetration_percent", inter.exactPercent},
              {"steps", steps},
              {"dt", out.dt},
              {"dt_largest", out.dtLargest},
              {"sweeps_per_step", out.timing["iterations_per_step"]},
              {"time_per_step_s", steps > 0 ? wall / steps : 0.0},
              {"contact_updates_per_s", out.timing["contact_updates_per_s"]},
              {"phases", phases},
              {"peak_rss_mb", peakRssMb()},
              {"settings", out.backendSettings},
              {"history", out.timing["history"]}};
  return run;
}

nlohmann::json compareCase(const BenchDef& def, const std::string& name, core::ShapeKind shape,
                           const std::function<void(const std::string&)>& log, const study::RunProgressFn& progress) {
  const core::RunConfig cfg = baseConfig(def, shape);
  const compaction::Deposit dep = compaction::deposit(cfg.box, cfg.population, cfg.deposition, cfg.seed);
  nlohmann::json c = {{"n_grains", dep.grains.size()},
                      {"shape", std::string(core::toString(shape))},
                      {"box", cfg.box},
                      {"deposit_s", dep.seconds}};
  BackendRun nscd = runBackend(cfg, "nscd", dep, labelled(progress, name));
  if (log)
    log(fmt::format("  nscd: {:.1f} s, {} steps, reached {}", nscd.json["wall_s"].get<double>(),
                    nscd.json["steps"].get<long>(), nscd.outcome.reached));
  BackendRun bullet = runBackend(cfg, "bullet", dep, labelled(progress, name));
  if (log)
    log(fmt::format("  bullet: {:.1f} s, {} steps, reached {}", bullet.json["wall_s"].get<double>(),
                    bullet.json["steps"].get<long>(), bullet.outcome.reached));
  // From when on did Bullet stay at nscd's final interpenetration or lower? Not the first check
  // that is: the geometric deposit overlaps nothing, so every run starts at zero before the pile
  // loads. The answer is the first check after the last one above nscd's level (null if Bullet
  // ends above it).
  nlohmann::json bulletAtNscdOverlap = nullptr;
  const auto& history = bullet.outcome.history;
  for (auto it = history.rbegin(); it != history.rend() && it->interpenetrationPercent <= nscd.finalInterpenetration;
       ++it)
    bulletAtNscdOverlap = it->wallSeconds;
  bullet.json["time_to_nscd_interpenetration_s"] = bulletAtNscdOverlap;
  c["nscd"] = nscd.json;
  c["bullet"] = bullet.json;
  const bool both = nscd.outcome.reached && bullet.outcome.reached;
  c["ratio_time_to_equilibrium"] =
      both ? nlohmann::json(nscd.json["wall_s"].get<double>() / bullet.json["wall_s"].get<double>())
           : nlohmann::json(nullptr);
  c["ratio_wall_time"] = nscd.json["wall_s"].get<double>() / bullet.json["wall_s"].get<double>();
  return c;
}

/// Least-squares slope of log t against log n: the scaling exponent k of t_step ~ n^k.
double logLogSlope(const std::vector<double>& x, const std::vector<double>& y) {
  const double n = static_cast<double>(x.size());
  const double mx = std::accumulate(x.begin(), x.end(), 0.0) / n, my = std::accumulate(y.begin(), y.end(), 0.0) / n;
  double sxy = 0.0, sxx = 0.0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    sxy += (x[i] - mx) * (y[i] - my);
    sxx += (x[i] - mx) * (x[i] - mx);
  }
  return sxy / sxx;
}

/// The scaling series' box for about n spheres: W = 10 and h = 16 of `def`'s base, the periodic
/// length stretched so that n grains fit.
core::RunConfig stretchedConfig(const BenchDef& def, int n) {
  core::RunConfig cfg = baseConfig(def, core::ShapeKind::Sphere);
  cfg.deposition.grainCount = static_cast<std::size_t>(n);
  cfg.box.lengthX = n * cfg.population.meanGrainVolume(cfg.population.largeSize) /
                    (cfg.deposition.expectedSolidFraction * cfg.box.width * cfg.box.height);
  return cfg;
}

/// Time to equilibrium against n: nscd compacts each size to rest (or def.timeLimit) with the
/// bench's protocol and time step; `exponents` gets the least-squares slopes of log(wall time) and
/// log(CPU time) against log(n) over the points that reached equilibrium (null below two).
nlohmann::json restSeries(const BenchDef& def, nlohmann::json& exponents,
                          const std::function<void(const std::string&)>& log, const study::RunProgressFn& progress) {
  nlohmann::json points = nlohmann::json::array();
  std::vector<double> logN, logWall, logCpu;
  for (int n : def.restSizes) {
    core::RunConfig cfg = stretchedConfig(def, n);
    const compaction::Deposit dep = compaction::deposit(cfg.box, cfg.population, cfg.deposition, cfg.seed);
    const BackendRun run =
        runBackend(cfg, "nscd", dep, labelled(progress, fmt::format("rest n={}", dep.grains.size())));
    const double wall = run.json["wall_s"].get<double>();
    const double cpu = run.outcome.history.empty() ? 0.0 : run.outcome.history.back().stepCpuSeconds;
    points.push_back({{"n_grains", dep.grains.size()},
                      {"length_x", cfg.box.lengthX},
                      {"equilibrium_reached", run.outcome.reached},
                      {"wall_s", wall},
                      {"step_cpu_s", cpu},
                      {"steps", run.json["steps"]},
                      {"stages", run.json["stages"]}});
    if (run.outcome.reached) {
      logN.push_back(std::log(static_cast<double>(dep.grains.size())));
      logWall.push_back(std::log(wall));
      logCpu.push_back(std::log(cpu));
    }
    if (log)
      log(fmt::format("  rest n={}: {} after {:.1f} s ({} steps)", dep.grains.size(),
                      run.outcome.reached ? "at rest" : "NOT at rest", wall, run.json["steps"].get<long>()));
  }
  const bool fit = logN.size() >= 2;
  exponents = {{"wall", fit ? nlohmann::json(logLogSlope(logN, logWall)) : nlohmann::json(nullptr)},
               {"cpu", fit ? nlohmann::json(logLogSlope(logN, logCpu)) : nlohmann::json(nullptr)},
               {"points_at_rest", logN.size()}};
  return points;
}

nlohmann::json scalingSeries(const BenchDef& def, nlohmann::json& exponents,
                             const std::function<void(const std::string&)>& log, const study::RunProgressFn& progress) {
  nlohmann::json points = nlohmann::json::array();
  std::map<std::string, std::vector<double>> logN, logT, logTPerSweep, logCpu;
  for (int n : def.scalingSizes) {
    core::RunConfig cfg = stretchedConfig(def, n);
    cfg.compaction.timeLimit = 1e9;
    const compaction::Deposit dep = compaction::deposit(cfg.box, cfg.population, cfg.deposition, cfg.seed);
    // Let the pile fall and load for scalingFall (rounded up to whole windows of scalingSteps),
    // then time one window of scalingSteps steps: the cost per step of a compaction is that of a
    // loaded pile (about 3 contact rows per grain), not of the first steps after the deposit.
    nlohmann::json point = {{"n_grains", dep.grains.size()}, {"length_x", cfg.box.lengthX}};
    for (const std::string backend : {"nscd", "bullet"}) {
      core::RunConfig c = cfg;
      c.backend = backend;
      c.compaction.protocol = core::Protocol::Dynamic;  // the series times dynamic steps
      const double dt = compaction::defaultTimeStep(c, dep);
      c.compaction.dt = dt;
      c.compaction.adaptiveDt = false;  // the window below counts fixed steps
      const long fallWindows = static_cast<long>(std::ceil(def.scalingFall / (def.scalingSteps * dt) - 1e-9));
      c.compaction.checkInterval = def.scalingSteps;
      c.compaction.timeLimit = static_cast<double>((fallWindows + 1) * def.scalingSteps) * dt;
      const compaction::CompactionOutcome out =
          compaction::compact(c, dep, {}, labelled(progress, fmt::format("scaling n={}", dep.grains.size())));
      // Over the timed window (between the two checks): time per step, solver iterations per
      // step, and the solve time per contact update (rows x iterations), which separates the
      // cost of one iteration from the number of them.
      const auto& h = out.history;
      if (h.empty()) throw std::runtime_error(fmt::format("bench scaling: {} stopped before its first check", backend));
      const compaction::CheckPoint first = h.size() >= 2 ? h[h.size() - 2] : compaction::CheckPoint{}, last = h.back();
      const double steps = static_cast<double>(last.steps - first.steps);
      const double perStep = (last.stepSeconds - first.stepSeconds) / steps;
      const double cpuPerStep = (last.stepCpuSeconds - first.stepCpuSeconds) / steps;
      const double iterations = static_cast<double>(last.iterations - first.iterations);
      const double rowUpdates = last.rowUpdates - first.rowUpdates;
      const double solveSeconds = last.solveSeconds - first.solveSeconds;
      point[backend] = {{"time_per_step_s", perStep},
                        {"cpu_per_step_s", cpuPerStep},
                        {"sweeps_per_step", iterations / steps},
                        {"contact_rows", iterations > 0.0 ? rowUpdates / iterations : 0.0},
                        {"solve_s_per_step", solveSeconds / steps},
                        {"solve_ns_per_contact_update", rowUpdates > 0.0 ? 1e9 * solveSeconds / rowUpdates : 0.0},
                        {"contact_updates_per_s", out.timing["contact_updates_per_s"]}};
      logN[backend].push_back(std::log(static_cast<double>(dep.grains.size())));
      logT[backend].push_back(std::log(perStep));
      logTPerSweep[backend].push_back(std::log(perStep * steps / std::max(1.0, iterations)));
      logCpu[backend].push_back(std::log(cpuPerStep));
      if (log)
        log(fmt::format("  scaling n={} {}: {:.3e} s/step, {:.0f} sweeps/step, {:.2f} contact rows per grain",
                        dep.grains.size(), backend, perStep, iterations / steps,
                        iterations > 0.0 ? rowUpdates / iterations / dep.grains.size() : 0.0));
    }
    points.push_back(point);
  }
  exponents = nlohmann::json::object();
  for (const auto& [backend, x] : logN)
    exponents[backend] = x.size() >= 2 ? nlohmann::json(logLogSlope(x, logT[backend])) : nlohmann::json(nullptr);
  // The same fit for the time of a step divided by its solver iterations: how the cost of one
  // iteration grows, apart from the number of iterations the configuration needs.
  nlohmann::json perSweep = nlohmann::json::object();
  for (const auto& [backend, x] : logN)
    perSweep[backend] = x.size() >= 2 ? nlohmann::json(logLogSlope(x, logTPerSweep[backend])) : nlohmann::json(nullptr);
  exponents["per_sweep"] = perSweep;
  // And for the CPU time per step: on a shared machine, other jobs inflate the wall time of some
  // points and not others.
  nlohmann::json cpu = nlohmann::json::object();
  for (const auto& [backend, x] : logN)
    cpu[backend] = x.size() >= 2 ? nlohmann::json(logLogSlope(x, logCpu[backend])) : nlohmann::json(nullptr);
  exponents["cpu"] = cpu;
  return points;
}

}  // namespace

namespace {

/// One target: its statement, what the run reached, and whether that meets it (null: not judged).
nlohmann::json target(std::string statement, std::string figure, std::optional<bool> met) {
  return {{"target", std::move(statement)},
          {"figure", std::move(figure)},
          {"met", met ? nlohmann::json(*met) : nlohmann::json(nullptr)}};
}

/// "882.0 s at rest" or "not at rest after 1800.0 s".
std::string restFigure(bool reached, double wall) {
  return reached ? fmt::format("{:.1f} s at rest", wall) : fmt::format("not at rest after {:.1f} s", wall);
}

constexpr double kHalfHour = 1800.0;  // [s]

}  // namespace

std::string targetLine(const nlohmann::json& t) {
  return fmt::format("{}: {} ({})", t["target"].get<std::string>(), t["figure"].get<std::string>(),
                     t["met"].is_null()     ? "not judged by this run"
                     : t["met"].get<bool>() ? "met"
                                            : "not met");
}

nlohmann::json benchTargets(const BenchDef& def, const nlohmann::json& cases) {
  nlohmann::json out = nlohmann::json::array();
  const bool fullSize = def.scale == 1.0;
  if (cases.contains("msp-w10")) {
    const nlohmann::json& nscd = cases["msp-w10"]["nscd"];
    const bool reached = nscd["equilibrium_reached"].get<bool>();
    const double wall = nscd["wall_s"].get<double>();
    // 60 s, and the multilevel solve's step on the way, 180 s (docs/performance.md, "Where the
    // speed targets stand"): judged on the full-size pile on one thread only.
    for (const double limit : {60.0, 180.0}) {
      std::optional<bool> met;
      if (fullSize && def.threads == 1) met = reached && wall <= limit;
      out.push_back(target(fmt::format("msp-w10: nscd at equilibrium in at most {:g} s on one thread", limit),
                           restFigure(reached, wall), met));
    }
  }
  if (cases.contains("mpp-w10")) {
    const nlohmann::json& nscd = cases["mpp-w10"]["nscd"];
    const bool reached = nscd["equilibrium_reached"].get<bool>();
    const double wall = nscd["wall_s"].get<double>();
    const double damping = nscd["settings"].value("damping", 0.0);
    std::string figure = restFigure(reached, wall);
    if (damping > 0.0) figure += fmt::format(", with damping {}", damping);
    std::optional<bool> met;
    if (fullSize) met = reached && damping == 0.0 && wall <= kHalfHour;
    out.push_back(target("mpp-w10: nscd at equilibrium without damping in at most 30 minutes", figure, met));
  }
  if (cases.contains("rest")) {
    // The largest point of the series stands for the 30,400-sphere target if it is that size.
    const nlohmann::json* largest = nullptr;
    for (const nlohmann::json& p : cases["rest"])
      if (!largest || p["n_grains"].get<double>() > (*largest)["n_grains"].get<double>()) largest = &p;
    if (largest) {
      const double n = (*largest)["n_grains"].get<double>();
      const bool reached = (*largest)["equilibrium_reached"].get<bool>();
      const double wall = (*largest)["wall_s"].get<double>();
      std::optional<bool> met;
      if (n >= 30000.0) met = reached && wall <= kHalfHour;
      out.push_back(target("rest: 30,400 spheres at equilibrium in at most 30 minutes",
                           fmt::format("{:.0f} spheres: {}", n, restFigure(reached, wall)), met));
    }
    const nlohmann::json& k = cases["rest_exponent"]["wall"];
    out.push_back(
        target("rest: time to equilibrium against n, t ~ n^k",
               k.is_null() ? std::string("fewer than two points at rest") : fmt::format("k = {:.2f}", k.get<double>()),
               std::nullopt));
  }
  if (cases.contains("scaling_exponent")) {
    const nlohmann::json& k = cases["scaling_exponent"]["nscd"];
    std::optional<bool> met;
    if (!k.is_null()) met = k.get<double>() <= 1.1;
    out.push_back(
        target("scaling: nscd's cost per step linear in n, exponent at most 1.1",
               k.is_null() ? std::string("fewer than two points") : fmt::format("k = {:.2f}", k.get<double>()), met));
  }
  return out;
}

const std::vector<std::string>& benchCaseNames() {
  static const std::vector<std::string> names = {"msp-w10", "mpp-w10", "scaling", "rest"};
  return names;
}

nlohmann::json runBench(const BenchDef& def, const std::function<void(const std::string&)>& log,
                        const study::RunProgressFn& progress) {
  nlohmann::json cases = nlohmann::json::object();
  for (const std::string& name : def.cases) {
    if (log) log(fmt::format("case {}", name));
    if (name == "msp-w10")
      cases[name] = compareCase(def, name, core::ShapeKind::Sphere, log, progress);
    else if (name == "mpp-w10")
      cases[name] = compareCase(def, name, core::ShapeKind::Pinacoid, log, progress);
    else if (name == "scaling") {
      nlohmann::json exponents;
      cases[name] = scalingSeries(def, exponents, log, progress);
      cases["scaling_exponent"] = exponents;  // t_step ~ n^k, least squares in log-log
    } else if (name == "rest") {
      nlohmann::json exponents;
      cases[name] = restSeries(def, exponents, log, progress);
      cases["rest_exponent"] = exponents;  // t_rest ~ n^k over the points at rest
    } else
      throw std::invalid_argument(
          fmt::format("unknown bench case '{}' (expected msp-w10, mpp-w10, scaling or rest)", name));
  }
  const nlohmann::json targets = benchTargets(def, cases);
  if (log)
    for (const nlohmann::json& t : targets) log("target " + targetLine(t));
  return {{"machine", machineInfo()}, {"cases", cases}, {"targets", targets}};
}

}  // namespace confpack::bench
