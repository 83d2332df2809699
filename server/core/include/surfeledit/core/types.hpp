// Basic vocabulary of the geometric core: array types, ids and the typed error.
//
// Eigen is the core's public vocabulary (as in libigl); no other third-party type
// (PCL, DDS) appears in a public header.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace surfeledit {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
// #P by 3, row-major so that a numpy (P, 3) C-contiguous float64 array maps onto it.
using Points = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
// #P values (radii, scale factors, ...).
using Values = Eigen::VectorXd;

// Stable surfel id: assigned once, never reused within a model, survives insertion and removal.
using SurfelId = std::uint64_t;
using IdList = std::vector<SurfelId>;
// Row index into a model's dense arrays (changes when surfels are removed).
using Index = std::int32_t;
using IndexList = std::vector<Index>;

// Kind of failure, mapped 1:1 to protocol status codes and Python exception classes.
enum class ErrorCode : std::uint8_t {
  InvalidArgument = 1,  // a value is malformed (NaN, wrong shape, unknown enum name, ...)
  NotFound = 2,         // an id, session or file does not exist
  Conflict = 3,         // the request is well-formed but contradicts the state (overlapping regions, ...)
  TooLarge = 4,         // beyond a documented size limit
  Io = 5,               // a file could not be read or written
  Internal = 6,         // a bug: an invariant of ours failed
};

const char* to_string(ErrorCode code);

// The one exception type of the core. `field` names the offending input (may be empty).
class Error : public std::runtime_error {
 public:
  Error(ErrorCode code, std::string field, const std::string& message);
  ErrorCode code() const { return code_; }
  const std::string& field() const { return field_; }

 private:
  ErrorCode code_;
  std::string field_;
};

// Throws Error(InvalidArgument, field, ...) naming the first non-finite entry of a
// rows by cols row-major array.
void require_finite(const double* data, Eigen::Index rows, Eigen::Index cols, const std::string& field);

template <typename Derived>
void require_finite(const Eigen::DenseBase<Derived>& a, const std::string& field) {
  if (a.allFinite()) return;
  const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> copy = a.template cast<double>();
  require_finite(copy.data(), copy.rows(), copy.cols(), field);
}

}  // namespace surfeledit
