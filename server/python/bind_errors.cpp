// Translates surfeledit::Error into the client's exception classes (surfeledit.errors),
// so in-process and server errors are caught the same way.
#include "common.hpp"

namespace surfeledit::py {
namespace {

const char* class_name(ErrorCode code) {
  switch (code) {
    case ErrorCode::InvalidArgument: return "InvalidArgumentError";
    case ErrorCode::NotFound: return "NotFoundError";
    case ErrorCode::Conflict: return "ConflictError";
    case ErrorCode::TooLarge: return "TooLargeError";
    case ErrorCode::Io: return "ServerIOError";
    case ErrorCode::Internal: return "InternalServerError";
  }
  return "SurfelEditError";
}

PyObject* fallback_class(ErrorCode code) {
  switch (code) {
    case ErrorCode::InvalidArgument: return PyExc_ValueError;
    case ErrorCode::NotFound: return PyExc_LookupError;
    case ErrorCode::Io: return PyExc_OSError;
    case ErrorCode::TooLarge: return PyExc_MemoryError;
    default: return PyExc_RuntimeError;
  }
}

}  // namespace

void bind_errors(pyb::module_&) {
  pyb::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Error& e) {
      pyb::object cls;
      try {
        cls = pyb::module_::import("surfeledit.errors").attr(class_name(e.code()));
      } catch (const pyb::error_already_set&) {
        PyErr_SetString(fallback_class(e.code()), e.what());
        return;
      }
      pyb::object exc = cls(e.what());
      pyb::setattr(exc, "status", pyb::int_(static_cast<int>(e.code())));
      pyb::setattr(exc, "field", pyb::str(e.field()));
      pyb::setattr(exc, "message", pyb::str(e.what()));
      PyErr_SetObject(cls.ptr(), exc.ptr());
    }
  });
}

}  // namespace surfeledit::py
