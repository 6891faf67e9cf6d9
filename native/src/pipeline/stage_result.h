// A stage's result together with the key of the inputs it was computed from.
//
// A stage runs again exactly when its key changes. Keys hold the ids of the upstream results they
// were computed from, so a new upstream result makes everything downstream stale without anyone
// resetting it by hand.
#pragma once
#include <atomic>
#include <cstdint>
#include <optional>
#include <utility>

namespace qgp {

// An id that differs for every result ever stored (0: none).
inline uint64_t next_stage_result_id() {
  static std::atomic<uint64_t> last{0};
  return ++last;
}

template <class T, class Key>
class StageResult {
 public:
  bool has_value() const { return value_.has_value(); }
  explicit operator bool() const { return value_.has_value(); }
  const T& operator*() const { return *value_; }
  const T* operator->() const { return &*value_; }
  T& operator*() { return *value_; }
  T* operator->() { return &*value_; }

  // True when the stored result was computed from inputs with this key.
  bool computed_from(const Key& key) const { return value_.has_value() && key_ == key; }
  const Key& key() const { return key_; }
  uint64_t id() const { return id_; }

  T& store(const Key& key, T value) {
    key_ = key;
    value_ = std::move(value);
    id_ = next_stage_result_id();
    return *value_;
  }

 private:
  std::optional<T> value_;
  Key key_{};
  uint64_t id_ = 0;
};

}  // namespace qgp
