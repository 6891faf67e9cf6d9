#include "core/error.h"

namespace qgp {

const char* error_code_name(ErrorCode code) {
  switch (code) {
    case ErrorCode::InvalidArgument: return "invalid_argument";
    case ErrorCode::InvalidMesh: return "invalid_mesh";
    case ErrorCode::UnreadableFile: return "unreadable_file";
    case ErrorCode::StageFailed: return "stage_failed";
    case ErrorCode::Cancelled: return "cancelled";
    case ErrorCode::Busy: return "busy";
    case ErrorCode::Internal: return "internal";
    case ErrorCode::NotReady: return "not_ready";
  }
  return "internal";
}

}  // namespace qgp
