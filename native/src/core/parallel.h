// Work shared out among threads in fixed chunks, so that each chunk's result is the same whatever
// the number of threads that ran them.
#pragma once
#include <algorithm>
#include <cstdlib>
#include <system_error>
#include <thread>
#include <vector>

namespace qgp {

// The machine's threads, or fewer where the environment's OMP_NUM_THREADS asks (the one setting that
// also caps CHOLMOD's and OpenBLAS's threads).
inline int machine_threads() {
  const int machine = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  const char* asked = std::getenv("OMP_NUM_THREADS");
  const int limit = asked ? std::atoi(asked) : 0;
  return limit > 0 ? std::min(machine, limit) : machine;
}

// Threads for `work` units of which each thread should get at least `min_work_per_thread`: at
// least 1, at most `threads` (0: machine_threads()) and 8.
inline int threads_for(double work, double min_work_per_thread, int threads = 0) {
  const int machine = threads > 0 ? threads : machine_threads();
  const int by_work = static_cast<int>(work / std::max(min_work_per_thread, 1.0));
  return std::max(1, std::min({machine, by_work, 8}));
}

// Runs task(0) ... task(chunks - 1): chunk 0 on the calling thread, the others on threads of their
// own. A chunk whose thread cannot be started runs on the calling thread after chunk 0. Returns
// when every chunk has run. Only the chunks on the calling thread may throw (a cancel check): the
// other threads are joined before the exception leaves.
template <class Task>
void run_chunks(int chunks, const Task& task) {
  struct Workers {
    std::vector<std::thread> threads;
    ~Workers() {
      for (std::thread& thread : threads) thread.join();
    }
  } workers;
  int started = 1;
  try {
    for (; started < chunks; ++started) workers.threads.emplace_back([&task, t = started] { task(t); });
  } catch (const std::system_error&) {  // no more threads to be had: the calling thread runs the rest
  }
  task(0);
  for (int t = started; t < chunks; ++t) task(t);
}

}  // namespace qgp
