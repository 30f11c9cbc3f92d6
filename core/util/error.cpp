#include "util/error.h"

namespace mcr {

const char* errc_name(Errc c) {
  switch (c) {
    case Errc::InvalidArgument: return "invalid_argument";
    case Errc::FileNotFound: return "file_not_found";
    case Errc::NotAnImage: return "not_an_image";
    case Errc::ReadFailed: return "read_failed";
    case Errc::WriteFailed: return "write_failed";
    case Errc::MissingPass: return "missing_pass";
    case Errc::SizeMismatch: return "size_mismatch";
    case Errc::UnknownFilter: return "unknown_filter";
    case Errc::UnknownParameter: return "unknown_parameter";
    case Errc::ParameterOutOfRange: return "parameter_out_of_range";
    case Errc::BadParameterValue: return "bad_parameter_value";
    case Errc::Internal: return "internal";
  }
  return "unknown";
}

}  // namespace mcr
