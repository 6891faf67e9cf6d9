// LD_PRELOAD shim for test_cli_abnormal_end.py: a library that ends the process with exit(0) a
// moment after it is loaded, as MUMPS does on an internal error ("** MPI_ABORT called", STOP).
#include <chrono>
#include <cstdlib>
#include <thread>

namespace {
struct ExitMidRun {
  ExitMidRun() {
    const char* delay = std::getenv("QGP_TEST_EXIT_AFTER_MS");
    if (!delay) return;
    const int ms = std::atoi(delay);
    std::thread([ms] {
      std::this_thread::sleep_for(std::chrono::milliseconds(ms));
      std::exit(0);
    }).detach();
  }
} exit_mid_run;
}  // namespace
