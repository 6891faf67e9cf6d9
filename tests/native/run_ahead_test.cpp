// Steps run ahead on a second thread (core/run_ahead.h): a search that takes them gets the results
// and the errors of running each step when asked for, in the same order, with or without the
// second thread; a result run ahead is used only for the step it was run for.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include "core/error.h"
#include "core/run_ahead.h"

namespace qgp {
namespace {

// A search like the flip rounds': step i's value depends on the state (the steps kept so far); a
// step is kept when its value is divisible by 3, and the next step asked for is then the same
// index on the new state, else the next index, up to `last`. Step `failing` throws. Returns the
// values taken, in order, and how many steps ran ahead.
struct Search {
  std::vector<std::string> taken;
  int run_ahead = 0;
};

Search search(bool second_thread, int last, int failing, std::atomic<int>* calls) {
  RunAhead<int> steps(second_thread);
  Progress progress;
  Search out;
  int state = 1;
  for (int index = 0, kept = 0; index <= last && kept < 6;) {
    const auto step = [&, state](int i, Progress& p) {
      p.check_cancel();
      if (calls) ++*calls;
      if (i == failing) throw Error(ErrorCode::StageFailed, "step " + std::to_string(i) + " failed");
      return (state * 7 + i * 5) % 11;
    };
    const auto not_kept = [](int v) { return v % 3 != 0; };
    int value = 0;
    try {
      value = steps.take(index, index < last, step, not_kept, progress);
    } catch (const Error& e) {
      out.taken.push_back(e.what());
      break;
    }
    out.taken.push_back(std::to_string(index) + ":" + std::to_string(value));
    if (value % 3 == 0) {
      steps.forget();
      state += value + 1;
      ++kept;
    } else {
      ++index;
    }
  }
  out.run_ahead = steps.steps_run_ahead();
  return out;
}

TEST(RunAhead, TakesTheStepsOfTheSearchInTurnWithOrWithoutASecondThread) {
  for (int last : {0, 1, 3, 8, 20}) {
    std::atomic<int> calls_alone{0};
    const Search alone = search(false, last, -1, &calls_alone);
    const Search beside = search(true, last, -1, nullptr);
    EXPECT_EQ(beside.taken, alone.taken) << "last step " << last;
    EXPECT_EQ(alone.run_ahead, 0);
    EXPECT_EQ(calls_alone.load(), static_cast<int>(alone.taken.size())) << "each step runs once, when asked for";
    if (last >= 3) EXPECT_GT(beside.run_ahead, 0) << "last step " << last;
  }
}

// The search above with 8 steps keeps some and goes on past others: a result run ahead is used
// after one not kept, and thrown away after one kept (a step then runs twice: the search asks for
// it again on the new state).
TEST(RunAhead, ResultsRunAheadAreUsedOnlyForTheStepTheyWereRunFor) {
  std::atomic<int> calls{0};
  const Search beside = search(true, 8, -1, &calls);
  const Search alone = search(false, 8, -1, nullptr);
  ASSERT_EQ(beside.taken, alone.taken);
  EXPECT_GE(calls.load(), static_cast<int>(beside.taken.size()));
  EXPECT_LE(calls.load(), static_cast<int>(beside.taken.size()) + beside.run_ahead);
}

// Step by step: a step run ahead is not run again when asked for (no step runs twice while none is
// kept), and after forget() (the state changed) it runs again on the new state.
TEST(RunAhead, AStepRunAheadRunsOnceAndAgainOnlyAfterForget) {
  RunAhead<int> steps(true);
  Progress progress;
  std::vector<int> calls(4, 0);
  int state = 0;
  const auto step = [&](int i, Progress&) {
    ++calls[i];
    return 10 * state + i;
  };
  const auto always = [](int) { return true; };
  EXPECT_EQ(steps.take(0, true, step, always, progress), 0);  // runs steps 0 and 1
  EXPECT_EQ(steps.take(1, true, step, always, progress), 1);  // step 1's result, run ahead
  EXPECT_EQ(steps.take(2, true, step, always, progress), 2);  // runs steps 2 and 3
  EXPECT_EQ(calls, (std::vector<int>{1, 1, 1, 1}));
  state = 1;  // step 2 kept
  steps.forget();
  EXPECT_EQ(steps.take(3, false, step, always, progress), 13);  // step 3 again, on the new state
  EXPECT_EQ(calls, (std::vector<int>{1, 1, 1, 2}));
  EXPECT_EQ(steps.steps_run_ahead(), 2);
}

// An error of a step run ahead is thrown only when that step is asked for, as it would have been
// thrown running it then; one that is never asked for is never seen.
TEST(RunAhead, AnErrorOfAStepRunAheadIsThrownWhenThatStepIsAskedFor) {
  for (int failing : {0, 1, 2, 5, 7}) {
    const Search alone = search(false, 8, failing, nullptr);
    const Search beside = search(true, 8, failing, nullptr);
    EXPECT_EQ(beside.taken, alone.taken) << "failing step " << failing;
  }
  RunAhead<int> steps(true);
  Progress progress;
  const auto step = [](int i, Progress&) {
    if (i == 1) throw Error(ErrorCode::StageFailed, "step 1 failed");
    return i;
  };
  const auto always = [](int) { return true; };
  EXPECT_EQ(steps.take(0, true, step, always, progress), 0);  // step 1 ran ahead and failed
  steps.forget();                                             // step 0 was kept: step 1 is not asked for
  EXPECT_EQ(steps.take(0, false, step, always, progress), 0);
  EXPECT_EQ(steps.steps_run_ahead(), 1);
  EXPECT_EQ(steps.take(0, true, step, always, progress), 0);
  EXPECT_THROW(steps.take(1, false, step, always, progress), Error);  // asked for after all
}

// A cancel reaches the step on the second thread through its progress without callback, and leaves
// from the calling thread's step.
TEST(RunAhead, ACancelStopsBothSteps) {
  std::atomic<bool> cancel{true};
  Progress progress([](const std::string&, double) {}, &cancel);
  RunAhead<int> steps(true);
  std::atomic<int> ahead_cancelled{0};
  const auto step = [&](int i, Progress& p) {
    try {
      p.check_cancel();
    } catch (const Error&) {
      if (i == 1) ++ahead_cancelled;
      throw;
    }
    return i;
  };
  const auto always = [](int) { return true; };
  try {
    steps.take(0, true, step, always, progress);
    ADD_FAILURE() << "no cancel";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::Cancelled);
  }
  EXPECT_EQ(ahead_cancelled.load(), 1);
}

// A step run ahead that the search will not ask for (needs_next is false for the step before it)
// is cancelled at once: the call returns without waiting for it to finish.
TEST(RunAhead, AStepRunAheadThatIsNotNeededIsCancelled) {
  RunAhead<int> steps(true);
  Progress progress;
  std::atomic<int> cancelled{0};
  const auto step = [&](int i, Progress& p) {
    if (i == 0) return 0;
    const auto start = std::chrono::steady_clock::now();
    while (std::chrono::steady_clock::now() - start < std::chrono::seconds(30)) {
      try {
        p.check_cancel();
      } catch (const Error&) {
        ++cancelled;
        throw;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    return i;
  };
  const auto never = [](int) { return false; };
  const auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(steps.take(0, true, step, never, progress), 0);
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(10));
  EXPECT_EQ(cancelled.load(), 1);
  EXPECT_EQ(steps.steps_run_ahead(), 1);
}

}  // namespace
}  // namespace qgp
