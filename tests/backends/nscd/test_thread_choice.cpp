// ThreadChoice (backends/nscd/thread_choice.hpp): the team is kept only while it is faster than
// one thread, and timed again every epoch.
#include <algorithm>
#include <catch2/catch.hpp>

#include "backends/nscd/thread_choice.hpp"

using namespace confpack;

TEST_CASE("nscd ThreadChoice keeps the faster of the team and one thread, and measures again every epoch",
          "[nscd][threads]") {
  using nscd::ThreadChoice;
  CHECK(ThreadChoice(1).next() == 1);
  for (const bool teamFaster : {true, false}) {
    ThreadChoice choice(2);
    const double teamTime = teamFaster ? 1e-3 : 8e-3, oneTime = 2e-3;
    int expectedLength = ThreadChoice::kEpoch;
    for (int epoch = 0; epoch < 3; ++epoch) {
      int teamCalls = 0, oneCalls = 0;
      int length = 0;
      int lengthSeen = 0;
      do {
        const int team = choice.next();
        REQUIRE((team == 1 || team == 2));
        if (length < ThreadChoice::kTrial) CHECK(team == 2);  // each epoch starts by timing both
        if (length >= ThreadChoice::kTrial && length < 2 * ThreadChoice::kTrial) CHECK(team == 1);
        (team == 2 ? teamCalls : oneCalls)++;
        choice.record(team == 2 ? teamTime : oneTime);
        if (++length == 2 * ThreadChoice::kTrial) lengthSeen = choice.epochLength();
      } while (length < 2 * ThreadChoice::kTrial || length < lengthSeen);
      // A losing team waits twice as long for its next trial; after the trials every call of the
      // epoch goes to the faster one.
      if (!teamFaster) expectedLength = std::min(2 * expectedLength, ThreadChoice::kMaxEpoch);
      CHECK(length == expectedLength);
      CHECK((teamFaster ? teamCalls : oneCalls) == length - ThreadChoice::kTrial);
    }
  }
}
