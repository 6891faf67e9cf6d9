// Wall-clock stopwatch for the per-stage timings of the report, and the process's peak memory.
#pragma once
#include <chrono>

namespace qgp {

class Timer {
 public:
  Timer() : start_(std::chrono::steady_clock::now()) {}
  double seconds() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(); }

 private:
  std::chrono::steady_clock::time_point start_;
};

// Peak resident memory of the whole process so far, in MB (core/timer.cpp). Inside a host (Blender
// without the worker process) it includes the host's own memory.
double peak_resident_mb();

}  // namespace qgp
