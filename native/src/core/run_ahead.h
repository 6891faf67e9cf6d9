// Steps of a search that go on to a known next step whenever one is not kept (the flip rounds' next
// ring): that next step runs beside the current one on a second thread, and its result waits for
// the call that asks for it; it is cancelled as soon as the current one's result shows the search
// will not ask for it. The steps asked for are the ones the search would run in turn, so its
// results are the same whatever the number of threads; only the time differs.
#pragma once
#include <atomic>
#include <exception>
#include <memory>
#include <utility>

#include "core/parallel.h"
#include "core/progress.h"

namespace qgp {

template <class Result>
class RunAhead {
 public:
  // `second_thread`: whether a next step may run beside the current one (false: each runs when
  // asked for, on the calling thread).
  explicit RunAhead(bool second_thread = machine_threads() > 1) : second_thread_(second_thread) {}

  // The result of step(index, progress). When `next_may_follow`, step(index + 1, ...) runs beside
  // it on a second thread (with progress.without_callback()) and is kept for the next call with
  // index + 1, unless needs_next(result of step index) says the search does not go on to it: then
  // it is cancelled at once. What a step throws is thrown by the call that asks for it. `step` must
  // not change anything both read.
  template <class Step, class NeedsNext>
  Result take(int index, bool next_may_follow, const Step& step, const NeedsNext& needs_next, Progress& progress) {
    if (!(ahead_ && ahead_index_ == index)) run(index, second_thread_ && next_may_follow, step, needs_next, progress);
    const std::unique_ptr<Outcome> outcome = std::move(ahead_);
    ahead_ = std::move(next_);  // leaves next_ empty
    ahead_index_ = index + 1;
    if (outcome->error) std::rethrow_exception(outcome->error);
    return std::move(*outcome->result);
  }
  // What the steps read changed (a step was kept): a result run ahead is of no use.
  void forget() { ahead_.reset(); }
  // Steps that ran ahead (their result used or not).
  int steps_run_ahead() const { return run_ahead_; }

 private:
  struct Outcome {
    std::unique_ptr<Result> result;
    std::exception_ptr error;
  };

  template <class Step, class NeedsNext>
  void run(int index, bool with_next, const Step& step, const NeedsNext& needs_next, Progress& progress) {
    ahead_ = std::make_unique<Outcome>(), ahead_index_ = index;
    next_.reset();
    if (with_next) next_ = std::make_unique<Outcome>(), ++run_ahead_;
    std::atomic<bool> not_needed{false};
    run_chunks(with_next ? 2 : 1, [&](int chunk) {
      Outcome& outcome = chunk == 0 ? *ahead_ : *next_;
      Progress silent = progress.without_callback(&not_needed);
      try {
        outcome.result = std::make_unique<Result>(step(index + chunk, chunk == 0 ? progress : silent));
        if (chunk == 0) not_needed = !needs_next(*outcome.result);
      } catch (...) {
        outcome.error = std::current_exception();
        if (chunk == 0) not_needed = true;  // the search ends with this error
      }
    });
    if (not_needed) next_.reset();
  }

  const bool second_thread_;
  std::unique_ptr<Outcome> ahead_, next_;  // the step asked for next (at ahead_index_), the one after
  int ahead_index_ = -1;
  int run_ahead_ = 0;
};

}  // namespace qgp
