#include "study/slurm.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <stdexcept>

#include "core/input_document.hpp"
#include "core/json_input.hpp"
#include "core/packing_io.hpp"
#include "study/process.hpp"
#include "study/run_claim.hpp"

namespace confpack::study {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr std::string_view kSubmissionsFormat = "confpack-slurm-submissions";

[[noreturn]] void refuse(std::string_view option, std::string_view what) {
  throw std::invalid_argument(fmt::format("{}: {}", option, what));
}

// Words that go into an #SBATCH line unquoted: sbatch splits those lines at white space.
bool plainWord(const std::string& s) {
  static const std::regex word("[A-Za-z0-9_.,:+@-]+");
  return std::regex_match(s, word);
}

// '...' for bash, a ' inside written as '\''.
std::string shellQuoted(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

// Options the script sets itself, or that have a flag of their own: refused in an extra line.
const std::map<std::string, std::string>& reservedOptions() {
  static const std::map<std::string, std::string> m = {
      {"--array", "the array is the unfinished runs'"},
      {"-a", "the array is the unfinished runs'"},
      {"--output", "logs go to SWEEPDIR/slurm/logs, where --status reads them"},
      {"-o", "logs go to SWEEPDIR/slurm/logs, where --status reads them"},
      {"--error", "logs go to SWEEPDIR/slurm/logs, where --status reads them"},
      {"-e", "logs go to SWEEPDIR/slurm/logs, where --status reads them"},
      {"--cpus-per-task", "use --cpus-per-task"},
      {"-c", "use --cpus-per-task"},
      {"--partition", "use --partition"},
      {"-p", "use --partition"},
      {"--time", "use --time"},
      {"-t", "use --time"},
      {"--mem", "use --mem"},
      {"--account", "use --account"},
      {"-A", "use --account"}};
  return m;
}

std::string readText(const fs::path& p) {
  std::ifstream in(p);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

std::string trimmed(std::string_view s) {
  const std::size_t a = s.find_first_not_of(" \t\r\n");
  if (a == std::string_view::npos) return "";
  const std::size_t b = s.find_last_not_of(" \t\r\n");
  return std::string(s.substr(a, b - a + 1));
}

}  // namespace

void checkSlurmOptions(const SlurmOptions& opt) {
  if (!opt.partition.empty() && !plainWord(opt.partition))
    refuse("--partition", fmt::format("expected a partition name (got '{}')", opt.partition));
  if (!opt.account.empty() && !plainWord(opt.account))
    refuse("--account", fmt::format("expected an account name (got '{}')", opt.account));
  // sbatch's forms: MM, MM:SS, HH:MM:SS, D-HH, D-HH:MM, D-HH:MM:SS; or no limit.
  static const std::regex time(R"(\d+(:\d+){0,2}|\d+-\d+(:\d+){0,2}|UNLIMITED|INFINITE)");
  if (!opt.time.empty() && !std::regex_match(opt.time, time))
    refuse("--time", fmt::format("expected MM, MM:SS, HH:MM:SS, D-HH, D-HH:MM or D-HH:MM:SS (got '{}')", opt.time));
  static const std::regex mem(R"([1-9]\d*[KMGT]?)");
  if (!opt.mem.empty() && !std::regex_match(opt.mem, mem))
    refuse("--mem", fmt::format("expected a positive integer with an optional unit K, M, G or T (got '{}')", opt.mem));
  if (opt.cpusPerTask < 1) refuse("--cpus-per-task", fmt::format("must be >= 1 (got {})", opt.cpusPerTask));
  if (opt.arrayLimit < 0) refuse("--array-limit", fmt::format("must be >= 0 (got {})", opt.arrayLimit));
  for (const std::string& line : opt.extraLines) {
    if (line.find_first_of("\n\r") != std::string::npos) refuse("--sbatch-line", "must be one line");
    if (line.empty() || line[0] != '-')
      refuse("--sbatch-line", fmt::format("expected an sbatch option such as --qos=long (got '{}')", line));
    const std::string name = line.substr(0, line.find_first_of("= \t"));
    if (const auto it = reservedOptions().find(name); it != reservedOptions().end())
      refuse("--sbatch-line", fmt::format("{}: not here ({})", name, it->second));
  }
}

void checkSlurmPath(const fs::path& sweepDir) {
  const std::string p = fs::absolute(sweepDir).lexically_normal().string();
  if (p.find_first_of(" \t\n\r'\"%\\") != std::string::npos)
    throw std::invalid_argument(
        fmt::format("--out: '{}' cannot go into an #SBATCH line (white space, a quote, '%' or '\\'): choose another "
                    "folder for a Slurm sweep",
                    p));
}

std::vector<ArrayTask> planArrayTasks(const std::vector<SweepRun>& runs, const std::vector<std::size_t>& todo,
                                      std::size_t maxTasks, const std::vector<std::optional<std::size_t>>& partners) {
  // One run a task: the study takes as long as its slowest run, not as its slowest deposit group
  // (up to 8 runs in series). A run reads its deposit or makes it, the same bytes either way (a
  // function of its configuration and seed); two tasks that make one at once both write it whole.
  // With equal_time a run and its partner share a task: the run needs the partner's fall time.
  std::vector<std::size_t> ordered = todo;
  std::sort(ordered.begin(), ordered.end());
  std::vector<std::vector<std::size_t>> units;  // dealt in table order of their first run
  std::map<std::size_t, std::size_t> unitOf;    // a partner's run index -> its unit
  for (std::size_t i : ordered) {
    const std::size_t key = i < partners.size() && partners[i] ? *partners[i] : i;
    const auto [it, added] = unitOf.try_emplace(key, units.size());
    if (added) units.emplace_back();
    units[it->second].push_back(i);
  }
  const std::size_t count = maxTasks > 0 ? std::min(maxTasks, units.size()) : units.size();
  std::vector<std::vector<std::size_t>> dealt(count);
  for (std::size_t j = 0; j < units.size(); ++j)
    dealt[j % count].insert(dealt[j % count].end(), units[j].begin(), units[j].end());
  std::vector<ArrayTask> tasks(count);
  for (std::size_t t = 0; t < count; ++t) {
    std::sort(dealt[t].begin(), dealt[t].end());  // each task's runs in table order
    for (std::size_t i : dealt[t]) tasks[t].runs.push_back(runs.at(i).name);
  }
  return tasks;
}

std::string sbatchScript(const SlurmOptions& opt, const std::vector<ArrayTask>& tasks, const fs::path& confpack,
                         const fs::path& sweepDir, std::string_view sweepName) {
  if (tasks.empty()) throw std::invalid_argument("no runs to submit");
  const fs::path dir = fs::absolute(sweepDir).lexically_normal();
  std::size_t runCount = 0;
  for (const ArrayTask& t : tasks) runCount += t.runs.size();
  std::string jobName = "confpack-" + std::string(sweepName);
  for (char& c : jobName)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_' && c != '.') c = '_';

  std::string s = "#!/bin/bash\n";
  s += fmt::format(
      "# The unfinished runs of sweep {} as a Slurm job array, written by `confpack sweep --slurm`: {} run{} in {} "
      "task{}.\n"
      "# Each task runs `confpack sweep SWEEPDIR --runs LIST`, which skips a run that is finished or held by a "
      "live task, so no run is done twice. docs/cluster.md.\n",
      sweepName, runCount, runCount == 1 ? "" : "s", tasks.size(), tasks.size() == 1 ? "" : "s");
  s += fmt::format("#SBATCH --job-name={}\n", jobName);
  s += fmt::format("#SBATCH --array=0-{}{}\n", tasks.size() - 1,
                   opt.arrayLimit > 0 ? fmt::format("%{}", opt.arrayLimit) : std::string());
  s += fmt::format("#SBATCH --output={}/slurm/logs/%A_%a.out\n", dir.string());
  s += fmt::format("#SBATCH --cpus-per-task={}\n", opt.cpusPerTask);
  if (!opt.time.empty()) s += fmt::format("#SBATCH --time={}\n", opt.time);
  if (!opt.mem.empty()) s += fmt::format("#SBATCH --mem={}\n", opt.mem);
  if (!opt.partition.empty()) s += fmt::format("#SBATCH --partition={}\n", opt.partition);
  if (!opt.account.empty()) s += fmt::format("#SBATCH --account={}\n", opt.account);
  for (const std::string& line : opt.extraLines) s += fmt::format("#SBATCH {}\n", line);
  s += "set -euo pipefail\n";
  s += "runs=(\n";
  for (const ArrayTask& t : tasks) {
    std::string list;
    for (const std::string& r : t.runs) list += (list.empty() ? "" : ",") + r;
    s += "  " + list + "\n";
  }
  s += ")\n";
  // Runs are single-threaded: as many at once as the task has CPUs.
  s += fmt::format("exec {} sweep {} --runs \"${{runs[$SLURM_ARRAY_TASK_ID]}}\" --jobs {}\n",
                   shellQuoted(fs::absolute(confpack).lexically_normal().string()), shellQuoted(dir.string()),
                   opt.cpusPerTask);
  return s;
}

std::string jobIdFromSbatch(std::string_view output) {
  // --parsable prints "JOBID" or "JOBID;CLUSTER"; warnings may come before it on stderr.
  static const std::regex id(R"((\d+)(;\S+)?)");
  std::string found;
  std::size_t at = 0;
  while (at <= output.size()) {
    const std::size_t end = std::min(output.find('\n', at), output.size());
    const std::string line = trimmed(output.substr(at, end - at));
    std::smatch m;
    if (std::regex_match(line, m, id)) found = m[1];
    at = end + 1;
  }
  if (found.empty())
    throw std::runtime_error(fmt::format("sbatch printed no job id (its output: '{}')", trimmed(output)));
  return found;
}

std::string submitBatch(const fs::path& script) {
  const fs::path out = privateFileName(script.parent_path(), "sbatch");
  const ProcessResult r =
      runProcess({"sbatch", "--parsable", script.string()}, {script.parent_path(), out, kSlurmCommandTimeout});
  const std::string text = readText(out);
  fs::remove(out);
  if (!r.ok())
    throw std::runtime_error(fmt::format("sbatch {}{}", r.describe(kSlurmCommandTimeout),
                                         trimmed(text).empty() ? "" : ": " + trimmed(text)));
  return jobIdFromSbatch(text);
}

std::optional<std::string> slurmJobState(const std::string& job) {
  const fs::path out = privateFileName(fs::temp_directory_path(), "squeue");
  const ProcessResult r = runProcess({"squeue", "--noheader", "--states=all", "--jobs", job, "--format=%T"},
                                     {{}, out, kSlurmCommandTimeout});
  const std::string text = readText(out);
  fs::remove(out);
  // A job Slurm has forgotten (past MinJobAge) is refused as an invalid id: it has ended.
  if (!r.ok()) return text.find("Invalid job id") != std::string::npos ? std::optional<std::string>("") : std::nullopt;
  return trimmed(text.substr(0, text.find('\n')));
}

bool isLiveJobState(std::string_view state) {
  static const std::set<std::string, std::less<>> live = {
      "PENDING",     "RUNNING",      "SUSPENDED", "COMPLETING", "CONFIGURING", "RESIZING",      "REQUEUED",
      "REQUEUE_FED", "REQUEUE_HOLD", "SIGNALING", "STAGE_OUT",  "STOPPED",     "RESV_DEL_HOLD", "SPECIAL_EXIT"};
  return live.count(state) > 0;
}

void recordSubmission(const fs::path& sweepDir, const Submission& s) {
  json doc = {{"format", kSubmissionsFormat}, {"version", 1}, {"submissions", json::array()}};
  for (const Submission& old : readSubmissions(sweepDir)) {
    json tasks = json::array();
    for (const ArrayTask& t : old.tasks) tasks.push_back(t.runs);
    doc["submissions"].push_back({{"job", old.job}, {"submitted", old.submitted}, {"tasks", tasks}});
  }
  json tasks = json::array();
  for (const ArrayTask& t : s.tasks) tasks.push_back(t.runs);
  doc["submissions"].push_back(
      {{"job", s.job}, {"submitted", s.submitted.empty() ? utcTimestamp() : s.submitted}, {"tasks", tasks}});
  fs::create_directories(sweepDir / "slurm");
  core::writeFileAtomically(sweepDir / "slurm" / "submitted.json", doc.dump(1));
}

std::vector<Submission> readSubmissions(const fs::path& sweepDir) {
  const fs::path file = sweepDir / "slurm" / "submitted.json";
  if (!fs::exists(file)) return {};
  const json doc = core::readJsonFile(file, "Slurm submissions");
  const core::ObjectReader top =
      core::readDocument(doc, file.string(), {kSubmissionsFormat, 1}, {"format", "version", "submissions"});
  std::vector<Submission> out;
  for (const json& j : top.array("submissions")) {
    const core::ObjectReader r(j, file.string(), fmt::format("submissions[{}]", out.size()));
    r.onlyKeys({"job", "submitted", "tasks"});
    Submission s;
    s.job = r.string("job");
    if (r.has("submitted")) s.submitted = r.string("submitted");
    for (const json& t : r.array("tasks")) {
      ArrayTask task;
      if (!t.is_array()) r.refuse("tasks", "must be an array of arrays of run names");
      for (const json& run : t) {
        if (!run.is_string()) r.refuse("tasks", "must be an array of arrays of run names");
        task.runs.push_back(run.get<std::string>());
      }
      s.tasks.push_back(std::move(task));
    }
    out.push_back(std::move(s));
  }
  return out;
}

fs::path taskLog(const fs::path& sweepDir, const std::string& task) {
  return sweepDir / "slurm" / "logs" / (task + ".out");
}

}  // namespace confpack::study
