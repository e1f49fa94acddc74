// `confpack deposit` (apps/cmd_deposit.cpp) stopped by a signal: the deposition's progress is its
// safe point.
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <string>
#include <thread>

#include "tests/support/confpack_binary.hpp"
#include "tests/support/read_file.hpp"

namespace fs = std::filesystem;
using confpack::testing::ConfpackSession;
using confpack::testing::lineCount;

TEST_CASE("SIGTERM or SIGINT stops a deposit: one line saying where, exit 128 + signal, nothing written",
          "[apps][cli]") {
  // The failure this guards against: a deposit went on to write its 171,313 grains after SIGTERM, exit 0.
  // 250,000 grains take several seconds; the signal comes after half a second.
  for (const auto& [signal, code, name] : {std::tuple{SIGTERM, 143, "SIGTERM"}, std::tuple{SIGINT, 130, "SIGINT"}}) {
    INFO(name);
    const ConfpackSession s("cmd_deposit_signal");
    const fs::path err = s.dir.string() + ".err";
    const pid_t pid = confpack::testing::startConfpack(
        s.dir, {"deposit", "--length-x", "60", "--width", "60", "--height", "60", "--out", "out", "-q"}, err);
    REQUIRE(pid >= 0);
    const confpack::testing::Stopped stopped =
        confpack::testing::stopAfter(pid, std::chrono::milliseconds(500), signal, err);
    const int status = stopped.status;
    const std::string& message = stopped.message;
    INFO(message);
    REQUIRE(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == code);
    CHECK(lineCount(message) == 1);
    CHECK(message.find(std::string("confpack deposit: error: interrupted by ") + name +
                       " while depositing (placeholder ") != std::string::npos);
    CHECK(s.empty());  // neither out/ nor its staging folder
  }
}
