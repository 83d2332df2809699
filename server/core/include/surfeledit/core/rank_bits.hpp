// A set of rows as one bit per row with the rank (how many set rows come before) of every row in
// O(1) (internal header): 1 bit per row plus 4 bytes per 64 rows, where a row -> index map of int32
// takes 32 bits per row (issue 14, memory). For per-row data kept for some rows only, in row order:
// the data of a set row r is at rank(r).
#pragma once

#include <cstdint>
#include <vector>

#include "surfeledit/core/types.hpp"

namespace surfeledit::detail {

class RankBits {
 public:
  // `rows` rows, none set.
  void assign(Index rows) {
    rows_ = rows;
    words_.assign(static_cast<std::size_t>((rows + 63) / 64), 0);
    before_.assign(words_.size(), 0);
    set_ = 0;
  }
  // `rows` rows, the ascending rows `set` set.
  void assign(Index rows, const IndexList& set) {
    assign(rows);
    for (Index r : set) words_[static_cast<std::size_t>(r) >> 6] |= bit(r);
    recount();
  }
  Index rows() const { return rows_; }
  Index count() const { return set_; }  // set rows
  bool test(Index r) const { return (words_[static_cast<std::size_t>(r) >> 6] & bit(r)) != 0; }
  // Set rows before r.
  Index rank(Index r) const {
    const std::size_t w = static_cast<std::size_t>(r) >> 6;
    return static_cast<Index>(before_[w]) + __builtin_popcountll(words_[w] & (bit(r) - 1));
  }
  // Appends a row, set or not.
  void push_back(bool set) {
    if ((rows_ & 63) == 0) {
      words_.push_back(0);
      before_.push_back(static_cast<std::uint32_t>(set_));
    }
    if (set) {
      words_.back() |= bit(rows_);
      ++set_;
    }
    ++rows_;
  }
  // Keeps the rows with keep[r] (one flag per row), in order.
  void compact(const std::vector<bool>& keep) {
    IndexList set;
    Index w = 0;
    for (Index r = 0; r < rows_; ++r) {
      if (!keep[static_cast<std::size_t>(r)]) continue;
      if (test(r)) set.push_back(w);
      ++w;
    }
    assign(w, set);
  }
  // The set rows, ascending.
  IndexList list() const {
    IndexList out;
    out.reserve(static_cast<std::size_t>(set_));
    for (Index r = 0; r < rows_; ++r)
      if (test(r)) out.push_back(r);
    return out;
  }
  std::size_t memory_bytes() const {
    return words_.capacity() * sizeof(std::uint64_t) + before_.capacity() * sizeof(std::uint32_t);
  }

 private:
  static std::uint64_t bit(Index r) { return std::uint64_t{1} << (static_cast<unsigned>(r) & 63u); }
  void recount() {
    Index n = 0;
    for (std::size_t w = 0; w < words_.size(); ++w) {
      before_[w] = static_cast<std::uint32_t>(n);
      n += __builtin_popcountll(words_[w]);
    }
    set_ = n;
  }

  Index rows_ = 0;
  Index set_ = 0;
  std::vector<std::uint64_t> words_;   // bit r & 63 of word r / 64: row r is set
  std::vector<std::uint32_t> before_;  // per word: set rows in the words before it
};

}  // namespace surfeledit::detail
