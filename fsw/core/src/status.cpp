#include "swf/core/status.hpp"

namespace swf::core {

const char* ToString(Status status) {
  switch (status) {
    case Status::kOk: return "ok";
    case Status::kInvalidArgument: return "invalid argument";
    case Status::kNotConfigured: return "not configured";
    case Status::kFull: return "full";
    case Status::kEmpty: return "empty";
    case Status::kTimeout: return "timeout";
    case Status::kNotConverged: return "not converged";
    case Status::kNumericalFailure: return "numerical failure";
    case Status::kCorruptData: return "corrupt data";
    case Status::kIoError: return "i/o error";
    case Status::kDeviceLost: return "device lost";
    case Status::kUnsupported: return "unsupported";
  }
  return "unknown status";
}

}  // namespace swf::core
