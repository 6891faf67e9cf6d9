// Progress reporting and cooperative cancellation, passed through every long-running stage.
#pragma once
#include <atomic>
#include <functional>
#include <string>

namespace qgp {

class Progress {
 public:
  // callback(stage, fraction in [0,1]); cancel: set by another thread to stop the work.
  using Callback = std::function<void(const std::string& stage, double fraction)>;

  Progress() = default;
  Progress(Callback callback, const std::atomic<bool>* cancel) : callback_(std::move(callback)), cancel_(cancel) {}

  // Enters a named stage (fraction 0). Throws Error(Cancelled) if cancel was requested.
  void begin_stage(const std::string& stage);
  // Reports the fraction of the current stage done. Throws Error(Cancelled) if requested.
  void update(double fraction);
  // Maps the fractions of later update() calls into [begin, end] of the current stage (e.g. one
  // component's share of it); begin_stage() resets the range to [0, 1].
  void set_range(double begin, double end) { range_begin_ = begin, range_end_ = end; }
  // Throws Error(Cancelled) if cancel was requested; call it often in loops (well below 1 s apart).
  void check_cancel() const;
  bool cancel_requested() const {
    return (cancel_ && cancel_->load(std::memory_order_relaxed)) ||
           (also_cancel_ && also_cancel_->load(std::memory_order_relaxed));
  }
  const std::string& stage() const { return stage_; }
  // The same stage and cancel flag, without the callback: for work on another thread (a callback
  // may only be called from the thread that owns it); `also`, when given, cancels it too.
  Progress without_callback(const std::atomic<bool>* also = nullptr) const;

 private:
  Callback callback_;
  const std::atomic<bool>* cancel_ = nullptr;
  const std::atomic<bool>* also_cancel_ = nullptr;
  std::string stage_;
  double range_begin_ = 0, range_end_ = 1;
};

}  // namespace qgp
