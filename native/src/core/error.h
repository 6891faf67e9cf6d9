// Errors raised by the native pipeline. Every C API entry point turns them into codes.
#pragma once
#include <stdexcept>
#include <string>

namespace qgp {

enum class ErrorCode {
  InvalidArgument = 1,  // a caller passed something malformed (option value, array size, ...)
  InvalidMesh = 2,      // the mesh is unusable (NaN, bad index, non-manifold edge, ...)
  UnreadableFile = 3,   // the file cannot be opened or parsed
  StageFailed = 5,      // a stage ran but could not produce a valid result
  Cancelled = 6,        // the caller cancelled the job
  Busy = 7,             // a job is already running on this session
  Internal = 8,         // a bug: an unexpected exception
  NotReady = 9,         // no result of the requested kind is available
};

// Stable lower-case name used in JSON reports ("invalid_mesh", ...).
const char* error_code_name(ErrorCode code);

class Error : public std::runtime_error {
 public:
  Error(ErrorCode code, const std::string& message) : std::runtime_error(message), code_(code) {}
  ErrorCode code() const { return code_; }

 private:
  ErrorCode code_;
};

}  // namespace qgp
