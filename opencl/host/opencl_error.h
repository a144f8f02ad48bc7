#pragma once

#include <stdexcept>
#include <string>

namespace gpucol::opencl {

/// An OpenCL call failed: carries the call's name, the error code and its name, and for program
/// builds the compiler's log. Thrown by the host layer, never asserted.
class OpenClError : public std::runtime_error {
 public:
  /// `context` says what the host layer was doing, `call` is the OpenCL function that failed.
  OpenClError(std::string context, std::string call, int code, std::string buildLog = {});

  /// Name of the OpenCL function that failed, e.g. "clBuildProgram".
  const std::string& call() const { return m_call; }
  /// The OpenCL error code, e.g. -5.
  int code() const { return m_code; }
  /// The error's name, e.g. "CL_OUT_OF_RESOURCES".
  const char* codeName() const;
  /// The compiler's log when a program build failed, else empty.
  const std::string& buildLog() const { return m_buildLog; }

 private:
  std::string m_call;
  int m_code;
  std::string m_buildLog;
};

/// Name of an OpenCL error code ("CL_INVALID_VALUE"), or "unknown OpenCL error" for codes the 3.0
/// headers do not define.
const char* clErrorName(int code);

}  // namespace gpucol::opencl
