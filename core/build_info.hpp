#pragma once
// What built this program, recorded in every result it writes (result.json, the profiles, the
// packing files, the benchmarks' output and the study report) so that a number can be traced back
// to the source that computed it.

namespace confpack::core {

/// The project's version, CMakeLists.txt's project(VERSION), e.g. "0.1.0".
const char* version();

/// The git commit the program was built from (12 hex digits), followed by "-dirty" when a tracked
/// file differed from that commit, or "unknown" when it was not built in a git checkout.
/// Generated at every build by cmake/source_revision.cmake.
const char* sourceRevision();

}  // namespace confpack::core
