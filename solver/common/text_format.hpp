#pragma once
/// \file text_format.hpp
/// Numbers in messages.

#include <cstdio>
#include <string>

namespace softkin {

/// v in printf's %g form with `significant` digits (6 by default, like std::ostream's default),
/// for error and progress messages.
inline std::string FormatNumber(double v, int significant = 6) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.*g", significant, v);
  return buf;
}

}  // namespace softkin
