#include "core/build_info.hpp"

// sourceRevision() is generated at build time (cmake/source_revision.cmake).
const char* confpack::core::version() {
  return CONFPACK_VERSION;
}
