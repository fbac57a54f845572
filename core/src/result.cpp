#include "shimmer/core/result.h"

namespace shimmer {

const char* ErrorCodeName(ErrorCode code) {
  switch (code) {
    case ErrorCode::kBadInput: return "bad input";
    case ErrorCode::kIo: return "I/O error";
    case ErrorCode::kDeviceLost: return "device lost";
    case ErrorCode::kOutOfMemory: return "out of memory";
    case ErrorCode::kBusy: return "busy";
    case ErrorCode::kInternal: return "internal error";
  }
  return "internal error";
}

}  // namespace shimmer
