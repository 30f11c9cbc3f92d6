#pragma once
// Typed errors: the core throws mcr::Error; each front end translates it once
// (CLI -> message + exit status, Python -> exception, OIIO plugin -> errorfmt).
#include <stdexcept>
#include <string>

namespace mcr {

enum class Errc {
  InvalidArgument,    // malformed option or value
  FileNotFound,       // input path does not exist
  NotAnImage,         // OpenImageIO cannot open it as an image
  ReadFailed,         // opened but pixels could not be read (truncated, corrupt)
  WriteFailed,        // output could not be written
  MissingPass,        // a pass a filter or command needs is absent
  SizeMismatch,       // passes or images of different sizes
  UnknownFilter,
  UnknownParameter,
  ParameterOutOfRange,
  BadParameterValue,  // value does not parse as the parameter's type
  Internal,
};

const char* errc_name(Errc c);

class Error : public std::runtime_error {
 public:
  Error(Errc code, const std::string& message) : std::runtime_error(message), code_(code) {}
  Errc code() const { return code_; }

 private:
  Errc code_;
};

// True for errors caused by the user's input (exit status 2 in the CLI).
inline bool is_user_error(Errc c) { return c != Errc::Internal; }

}  // namespace mcr
