// CPU seconds (user + sys) of the whole process so far: on a shared machine the comparable time.
// For the benchmark tools.
#pragma once

#include <sys/resource.h>

namespace lightvol::bench {

inline double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  const auto s = [](const timeval& t) {
    return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec);
  };
  return s(u.ru_utime) + s(u.ru_stime);
}

}  // namespace lightvol::bench
