// Claims on runs (study/run_claim.hpp): of processes racing for the same runs exactly one takes
// each, a dead holder's claim is broken once, a live holder's never, and a holder removes only its
// own claim.
#include <fmt/format.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "study/run_claim.hpp"
#include "tests/support/read_file.hpp"
#include "tests/support/scratch.hpp"

namespace fs = std::filesystem;
using namespace confpack;

namespace {

constexpr int kRuns = 200;

std::string runName(int i) {
  return "r" + std::to_string(1000 + i);
}

// Forks `n` children that wait at a start line (a pipe the parent closes), then each try to claim
// every run with `alive` judging holders, and write the runs they won to DIR/wonK. They keep their
// claims (they leave with _exit, no destructor), so that a run taken once stays taken.
void race(const fs::path& dir, int n, const study::LivenessFn& alive) {
  int gate[2];
  REQUIRE(::pipe(gate) == 0);
  std::vector<pid_t> children;
  for (int k = 0; k < n; ++k) {
    const pid_t pid = ::fork();
    REQUIRE(pid >= 0);
    if (pid == 0) {
      ::close(gate[1]);
      char c;
      while (::read(gate[0], &c, 1) > 0) {
      }
      std::ofstream won(dir / ("won" + std::to_string(k)));
      for (int i = 0; i < kRuns; ++i) {
        // Half the children go through the runs backwards: they meet the others in the middle.
        const int r = k % 2 == 0 ? i : kRuns - 1 - i;
        std::optional<study::RunClaim> claim = study::RunClaim::acquire(dir / "claims", runName(r), nullptr, alive);
        if (claim) {
          won << runName(r) << '\n';
          new study::RunClaim(std::move(*claim));  // kept to the end: never released
        }
      }
      won.close();
      ::_exit(0);
    }
    children.push_back(pid);
  }
  ::close(gate[0]);
  ::close(gate[1]);  // all start at once
  for (pid_t pid : children) {
    int status = 0;
    ::waitpid(pid, &status, 0);
    CHECK(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == 0);
  }
}

// Each run was won by exactly one child, and its claim file names that child's pid.
void checkEachRunTakenOnce(const fs::path& dir, int n) {
  std::multiset<std::string> won;
  std::vector<std::set<std::string>> byChild(n);
  for (int k = 0; k < n; ++k) {
    std::ifstream in(dir / ("won" + std::to_string(k)));
    for (std::string line; std::getline(in, line);) {
      won.insert(line);
      byChild[k].insert(line);
    }
  }
  CHECK(won.size() == kRuns);
  for (int i = 0; i < kRuns; ++i) {
    INFO(runName(i));
    CHECK(won.count(runName(i)) == 1);
  }
  // The contest was real: more than one child won runs.
  int winners = 0;
  for (const auto& s : byChild) winners += !s.empty();
  CHECK(winners > 1);
}

}  // namespace

TEST_CASE("claims: processes racing for the same runs take each exactly once") {
  const fs::path dir = confpack::testing::freshDir("claim_race");
  race(dir, 4, [](const study::ClaimHolder&) { return study::Liveness::Alive; });
  checkEachRunTakenOnce(dir, 4);
  // No private or break-lock file is left behind: one claim file per run.
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir / "claims")) files += e.path().filename().string()[0] != '.';
  int hidden = 0;
  for (const auto& e : fs::directory_iterator(dir / "claims")) hidden += e.path().filename().string()[0] == '.';
  CHECK(files == kRuns);
  CHECK(hidden == 0);
  fs::remove_all(dir);
}

TEST_CASE("claims: processes racing to break the same dead holders' claims take each run exactly once") {
  const fs::path dir = confpack::testing::freshDir("claim_break_race");
  fs::create_directories(dir / "claims");
  for (int i = 0; i < kRuns; ++i) {
    const study::ClaimHolder dead{"gone", 1, 0, "9_9", "stale-" + std::to_string(i), "2024-01-01T00:00:00Z"};
    std::ofstream(dir / "claims" / runName(i)) << study::toJson(dead).dump();
  }
  race(dir, 4, [](const study::ClaimHolder& h) {
    return h.token.rfind("stale-", 0) == 0 ? study::Liveness::Dead : study::Liveness::Alive;
  });
  checkEachRunTakenOnce(dir, 4);
  for (int i = 0; i < kRuns; ++i) {
    const auto h = study::readClaim(dir / "claims", runName(i));
    REQUIRE(h);
    CHECK(h->token.rfind("stale-", 0) != 0);
  }
  fs::remove_all(dir);
}

TEST_CASE("claims: a live holder on this host keeps its claim, a dead one or a reused pid loses it") {
  const fs::path dir = confpack::testing::freshDir("claim_liveness");
  const fs::path claims = dir / "claims";
  fs::create_directories(claims);
  const study::ClaimHolder me = study::currentProcess();
  REQUIRE(me.startTicks > 0);
  CHECK(study::holderLiveness(me) == study::Liveness::Alive);

  // A child that has exited and been reaped: its pid runs nothing (until reused).
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  ::waitpid(child, nullptr, 0);
  study::ClaimHolder dead = me;
  dead.pid = child;
  dead.token = "dead";
  CHECK(study::holderLiveness(dead) == study::Liveness::Dead);
  // Our own pid, but a process that started at another time: the pid was reused.
  study::ClaimHolder reused = me;
  reused.startTicks = me.startTicks + 1;
  reused.token = "reused";
  CHECK(study::holderLiveness(reused) == study::Liveness::Dead);
  // Another host without a Slurm job: nothing tells whether it lives.
  study::ClaimHolder far = me;
  far.host = me.host + "-elsewhere";
  far.job.clear();
  CHECK(study::holderLiveness(far) == study::Liveness::Unknown);

  // Our parent (the shell or ctest) is alive: its claim is kept, and named.
  study::ClaimHolder parent = me;
  parent.pid = ::getppid();
  parent.startTicks = 0;
  parent.token = "parent";
  std::ofstream(claims / "r0000") << study::toJson(parent).dump();
  study::ClaimHolder heldBy;
  CHECK_FALSE(study::RunClaim::acquire(claims, "r0000", &heldBy));
  CHECK(heldBy.token == "parent");
  CHECK(study::describe(heldBy) ==
        fmt::format("{} pid {}", me.host, ::getppid()) + (me.job.empty() ? "" : " (job " + me.job + ")"));
  // Far away and uncheckable: kept too (a claim is never broken on a guess).
  std::ofstream(claims / "r0001") << study::toJson(far).dump();
  CHECK_FALSE(study::RunClaim::acquire(claims, "r0001"));

  for (const study::ClaimHolder& h : {dead, reused}) {
    INFO(h.token);
    std::ofstream(claims / "r0002") << study::toJson(h).dump();
    std::optional<study::RunClaim> claim = study::RunClaim::acquire(claims, "r0002");
    REQUIRE(claim);
    CHECK(study::readClaim(claims, "r0002")->token == claim->holder().token);
    claim->release();
    CHECK_FALSE(fs::exists(claims / "r0002"));
  }
  fs::remove_all(dir);
}

TEST_CASE("claims: a holder gives up only its own claim") {
  const fs::path dir = confpack::testing::freshDir("claim_release");
  std::optional<study::RunClaim> claim = study::RunClaim::acquire(dir / "claims", "r0000");
  REQUIRE(claim);
  CHECK(study::readClaim(dir / "claims", "r0000")->pid == ::getpid());
  CHECK_FALSE(study::RunClaim::acquire(dir / "claims", "r0000"));  // held, by a live process: us
  // Someone broke it and claimed it meanwhile (as if we had been judged dead).
  study::ClaimHolder other = study::currentProcess();
  fs::remove(dir / "claims" / "r0000");
  std::ofstream(dir / "claims" / "r0000") << study::toJson(other).dump();
  claim.reset();  // the destructor releases: not the other's claim
  REQUIRE(study::readClaim(dir / "claims", "r0000"));
  CHECK(study::readClaim(dir / "claims", "r0000")->token == other.token);
  fs::remove_all(dir);
}
