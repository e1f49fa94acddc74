// Progress (apps/progress.hpp; docs/model.md, "Command line") when stderr is not a terminal: plain lines, at most one
// per interval, "label: " on every line, nothing at all when disabled.
#include <fcntl.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <functional>
#include <string>

#include "apps/progress.hpp"
#include "tests/support/confpack_binary.hpp"
#include "tests/support/read_file.hpp"
#include "tests/support/scratch.hpp"

using confpack::app::Progress;
using confpack::testing::lineCount;

namespace {

/// What `work` writes to stderr, which is a regular file (not a terminal) meanwhile.
std::string stderrOf(const std::function<void()>& work) {
  const auto dir = confpack::testing::freshDir("progress");
  std::fflush(stderr);
  const int saved = ::dup(STDERR_FILENO);
  const int file = ::open((dir / "stderr.txt").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  REQUIRE(saved >= 0);
  REQUIRE(file >= 0);
  ::dup2(file, STDERR_FILENO);
  ::close(file);
  work();
  std::fflush(stderr);
  ::dup2(saved, STDERR_FILENO);
  ::close(saved);
  const std::string text = confpack::testing::slurp(dir / "stderr.txt");
  std::filesystem::remove_all(dir);
  return text;
}

bool startsWith(const std::string& s, const std::string& prefix) {
  return s.compare(0, prefix.size(), prefix) == 0;
}

}  // namespace

TEST_CASE("progress to a file: one plain line per report, labelled, done and notes on lines of their own") {
  bool live = true;
  const std::string text = stderrOf([&] {
    Progress p("deposit", true, 0.0);  // no interval: every update is printed
    live = p.live();
    p.update(0.25, "1/4");
    p.update(1.5, "4/4");  // clamped to 100 %
    p.note("case begins");
    p.done("4 grains");
  });
  CHECK_FALSE(live);
  REQUIRE(lineCount(text) == 4);
  std::size_t pos = 0;
  std::string lines[4];
  for (auto& line : lines) {
    const std::size_t end = text.find('\n', pos);
    line = text.substr(pos, end - pos);
    pos = end + 1;
  }
  CHECK(startsWith(lines[0], "deposit: 25.0% 1/4 ["));
  CHECK(startsWith(lines[1], "deposit: 100.0% 4/4 ["));
  CHECK(lines[2] == "deposit: case begins");
  CHECK(startsWith(lines[3], "deposit: done 4 grains ["));
  CHECK(text.find('\r') == std::string::npos);  // no live-line control characters in a file
  CHECK(text.find('\033') == std::string::npos);
}

TEST_CASE("progress to a file prints at most one update per interval, and none when disabled") {
  const std::string throttled = stderrOf([] {
    Progress p("run", true, 3600.0);
    for (int k = 0; k <= 100; ++k) p.update(k / 100.0);  // the first one only, within the hour
    p.note("between stretches");
    p.update(0.5);  // after a note the next update is printed at once
    p.update(0.6);
  });
  CHECK(lineCount(throttled) == 3);
  CHECK(throttled.find("run: 50.0%") != std::string::npos);
  CHECK(throttled.find("run: 60.0%") == std::string::npos);
  const std::string silent = stderrOf([] {
    Progress p("quiet", false, 0.0);
    p.update(0.5, "half");
    p.note("nothing");
    p.done("nothing either");
  });
  CHECK(silent.empty());
}
