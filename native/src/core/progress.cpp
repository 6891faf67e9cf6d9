#include "core/progress.h"

#include <algorithm>

#include "core/error.h"

namespace qgp {

void Progress::begin_stage(const std::string& stage) {
  stage_ = stage;
  range_begin_ = 0, range_end_ = 1;
  check_cancel();
  if (callback_) callback_(stage_, 0.0);
}

void Progress::update(double fraction) {
  check_cancel();
  const double f = std::clamp(fraction, 0.0, 1.0);
  if (callback_) callback_(stage_, range_begin_ + f * (range_end_ - range_begin_));
}

Progress Progress::without_callback(const std::atomic<bool>* also) const {
  Progress silent(Callback(), cancel_);
  silent.also_cancel_ = also ? also : also_cancel_;
  silent.stage_ = stage_;
  return silent;
}

void Progress::check_cancel() const {
  if (cancel_requested()) throw Error(ErrorCode::Cancelled, "cancelled during stage '" + stage_ + "'");
}

}  // namespace qgp
