// Wall-clock stopwatch for the per-stage timings of the report, and the process's peak memory.
#pragma once
#include <sys/resource.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <string>

namespace qgp {

class Timer {
 public:
  Timer() : start_(std::chrono::steady_clock::now()) {}
  double seconds() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(); }

 private:
  std::chrono::steady_clock::time_point start_;
};

// Peak resident memory of the whole process so far, in MB. Linux: VmHWM of /proc/self/status, the
// high-water mark of this program's own memory (ru_maxrss would also carry the parent's resident
// memory at fork across the exec: a worker started by Blender holding a 2.25 M-triangle sculpt read
// 5.7 GB from it while it peaked at 1.0 GB); elsewhere ru_maxrss. Inside a host (Blender without the
// worker process) it includes the host's own memory.
inline double peak_resident_mb() {
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);)
    if (line.rfind("VmHWM:", 0) == 0) return std::strtod(line.c_str() + 6, nullptr) / 1024.0;  // "VmHWM:  123 kB"
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) != 0) return 0.0;
  return static_cast<double>(usage.ru_maxrss) / 1024.0;
}

}  // namespace qgp
