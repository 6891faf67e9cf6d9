// LD_PRELOAD shim for test_cli_abnormal_end.py: a library that ends the process with exit(0) once the
// process has used QGP_TEST_EXIT_AFTER_MS of CPU time, as MUMPS does on an internal error
// ("** MPI_ABORT called", STOP). CPU time, not wall time: on a loaded machine a wall-clock delay can
// end the process before the pipeline has started, which is not what the test is about.
#include <time.h>

#include <chrono>
#include <cstdlib>
#include <thread>

namespace {
double process_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

struct ExitMidRun {
  ExitMidRun() {
    const char* delay = std::getenv("QGP_TEST_EXIT_AFTER_MS");
    if (!delay) return;
    const double ms = std::atof(delay);
    std::thread([ms] {
      while (process_cpu_ms() < ms) std::this_thread::sleep_for(std::chrono::milliseconds(10));
      std::exit(0);
    }).detach();
  }
} exit_mid_run;
}  // namespace
