// Errors about a model file: under the field "path", the message naming the file first. Shared by the loaders
// (model_io.cpp, mesh_files.cpp) and the header checks (model_headers.cpp).
#pragma once

#include <string>

#include "surfeledit/core/types.hpp"

namespace surfeledit {

// Error(code, "path") with the message "'<path>': <what>".
inline Error file_error(ErrorCode code, const std::string& path, const std::string& what) {
  return Error(code, "path", "'" + path + "': " + what);
}

// Runs `check` (a validation of arrays read from the file at `path`) and throws what it throws as a file_error of
// the same code: the arrays came from that file, so the file is what the caller must fix.
template <class Check>
void checked_in_file(const std::string& path, Check&& check) {
  try {
    check();
  } catch (const Error& e) {
    throw file_error(e.code(), path, e.what());
  }
}

}  // namespace surfeledit
