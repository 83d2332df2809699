// A binary writer / reader pair for snapshots (docs/journal.md "Snapshots"): little-endian scalars,
// strings and arrays, appended to one byte buffer. The reader checks every length against the bytes
// that remain before allocating, so a truncated or corrupt buffer is an Error (InvalidArgument, field
// "snapshot", naming what was being read and the offset), never a crash or an unbounded allocation.
// Vectors keep their capacity (the history's memory bound counts capacities), bounded by a multiple
// of the buffer's size.
#pragma once

#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

#include "surfeledit/core/types.hpp"

namespace surfeledit {

class SnapshotWriter {
 public:
  void u8(std::uint8_t v) { raw(&v, 1); }
  void u32(std::uint32_t v) { raw(&v, sizeof v); }
  void u64(std::uint64_t v) { raw(&v, sizeof v); }
  void i64(std::int64_t v) { raw(&v, sizeof v); }
  void f64(double v) { raw(&v, sizeof v); }
  void boolean(bool v) { u8(v ? 1 : 0); }
  void str(const std::string& s) {
    u64(s.size());
    raw(s.data(), s.size());
  }
  // Size, capacity, then the elements' bytes (T trivially copyable).
  template <typename T>
  void vec(const std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    u64(v.size());
    u64(v.capacity());
    raw(v.data(), v.size() * sizeof(T));
  }
  // A dense Eigen matrix or vector: rows, cols, then its storage.
  template <typename M>
  void mat(const M& m) {
    u64(static_cast<std::uint64_t>(m.rows()));
    u64(static_cast<std::uint64_t>(m.cols()));
    raw(m.data(), static_cast<std::size_t>(m.size()) * sizeof(typename M::Scalar));
  }
  void raw(const void* p, std::size_t n) {
    if (n) buf_.append(static_cast<const char*>(p), n);
  }
  // Room for `n` bytes in all, so that a writer that knows about how much it will write grows its buffer once.
  void reserve(std::size_t n) { buf_.reserve(n); }
  const std::string& bytes() const { return buf_; }
  std::string take() { return std::move(buf_); }

 private:
  std::string buf_;
};

class SnapshotReader {
 public:
  SnapshotReader(const char* data, std::size_t size) : p_(data), n_(size) {}
  explicit SnapshotReader(const std::string& s) : SnapshotReader(s.data(), s.size()) {}

  std::uint8_t u8(const char* what) { return scalar<std::uint8_t>(what); }
  std::uint32_t u32(const char* what) { return scalar<std::uint32_t>(what); }
  std::uint64_t u64(const char* what) { return scalar<std::uint64_t>(what); }
  std::int64_t i64(const char* what) { return scalar<std::int64_t>(what); }
  double f64(const char* what) { return scalar<double>(what); }
  bool boolean(const char* what);
  std::string str(const char* what);
  // A count of items of at least `item_bytes` each that the rest of the buffer can hold.
  std::size_t count(const char* what, std::size_t item_bytes);
  template <typename T>
  std::vector<T> vec(const char* what) {
    static_assert(std::is_trivially_copyable_v<T>);
    const std::size_t size = count(what, sizeof(T));
    std::vector<T> v;
    v.reserve(capacity(what, size, sizeof(T)));
    v.resize(size);
    raw(v.data(), size * sizeof(T), what);
    return v;
  }
  // A matrix of the type of `M`; `cols` (> 0) is checked when the type has a fixed column count.
  template <typename M>
  M mat(const char* what) {
    const std::uint64_t rows = u64(what), cols = u64(what);
    if (M::ColsAtCompileTime > 0 && cols != static_cast<std::uint64_t>(M::ColsAtCompileTime) && !(rows == 0))
      fail(what, "has " + std::to_string(cols) + " columns");
    if (M::ColsAtCompileTime == 1 && cols != 1) fail(what, "is not a vector");
    if (cols > 0 && rows > remaining() / (cols * sizeof(typename M::Scalar)))
      fail(what, "larger than the bytes left");
    M m;
    const std::uint64_t c = M::ColsAtCompileTime > 0 ? static_cast<std::uint64_t>(M::ColsAtCompileTime) : cols;
    m.resize(static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(c));
    raw(m.data(), static_cast<std::size_t>(m.size()) * sizeof(typename M::Scalar), what);
    return m;
  }
  void raw(void* out, std::size_t n, const char* what);
  // Reads a capacity written for a vector of `size` items of `item` bytes: at least `size`, at most 8 x the
  // buffer plus 1 MiB in bytes.
  std::size_t capacity(const char* what, std::size_t size, std::size_t item) {
    const std::uint64_t cap = u64(what);
    if (cap < size || cap > capacity_bound(item)) fail(what, "capacity " + std::to_string(cap) + " out of bounds");
    return static_cast<std::size_t>(cap);
  }
  std::size_t remaining() const { return n_ - at_; }
  std::size_t offset() const { return at_; }
  // InvalidArgument (field "snapshot") unless every byte was read.
  void expect_end() const;
  // Throws the reader's error: `what` (at the current offset) and why.
  [[noreturn]] void fail(const char* what, const std::string& why) const;

 private:
  template <typename T>
  T scalar(const char* what) {
    T v;
    raw(&v, sizeof v, what);
    return v;
  }
  // Largest accepted capacity of a vector of `item` bytes: 8 x the buffer plus 1 MiB, in items.
  std::uint64_t capacity_bound(std::size_t item) const { return (8 * static_cast<std::uint64_t>(n_) + (1u << 20)) / item; }

  const char* p_;
  std::size_t n_;
  std::size_t at_ = 0;
};

}  // namespace surfeledit
