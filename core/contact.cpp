#include "core/contact.hpp"

#include <fmt/format.h>

#include <stdexcept>

namespace confpack::core {

std::string_view toString(ContactType t) {
  switch (t) {
    case ContactType::Simple:
      return "simple";
    case ContactType::Double:
      return "double";
    case ContactType::Triple:
      return "triple";
  }
  return "simple";
}

ContactType contactTypeFromString(std::string_view s) {
  if (s == "simple") return ContactType::Simple;
  if (s == "double") return ContactType::Double;
  if (s == "triple") return ContactType::Triple;
  throw std::invalid_argument(fmt::format("unknown contact type '{}' (expected simple, double or triple)", s));
}

}  // namespace confpack::core
