#include "core/progress.h"

#include <algorithm>

#include "core/error.h"

namespace qgp {

void Progress::begin_stage(const std::string& stage) {
  stage_ = stage;
  check_cancel();
  if (callback_) callback_(stage_, 0.0);
}

void Progress::update(double fraction) {
  check_cancel();
  if (callback_) callback_(stage_, std::clamp(fraction, 0.0, 1.0));
}

void Progress::check_cancel() const {
  if (cancel_requested()) throw Error(ErrorCode::Cancelled, "cancelled during stage '" + stage_ + "'");
}

}  // namespace qgp
