// The order in which a sweep answers its nearest-neighbour queries (internal header): the rows of a
// sweep sorted along a Morton (Z-order) curve of their positions when the order was built, so that
// consecutive queries descend the same paths of a k-d tree (its nodes cached, its branches predicted).
// Built once per set of rows (a detector's reset, or the first step after its rows changed), never per
// step; a sweep that uses it (ParallelSweep, row_detector.hpp) first settles every row that needs no
// query, in storage order, then makes the queries in this order. Each row's result is its own, so any
// order gives the same results; the order changes speed only (RESULTS §50).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "../collision_detail.hpp"

namespace surfeledit::detail {

class QueryOrder {
 public:
  // The indices q of rows[q] (rows of `positions`, #P by 3), ordered along the Morton curve of their
  // positions quantised to kBits bits per axis over the rows' bounding box; equal codes keep q order.
  QueryOrder(const Points& positions, const IndexList& rows) {
    const std::size_t n = rows.size();
    Vec3 lo = Vec3::Constant(0.0), hi = Vec3::Constant(0.0);
    for (std::size_t q = 0; q < n; ++q) {
      const Vec3 p = row3(positions, rows[q]);
      lo = q == 0 ? p : lo.cwiseMin(p);
      hi = q == 0 ? p : hi.cwiseMax(p);
    }
    // Cells per unit length on each axis; a flat or non-finite extent puts every row in cell 0.
    Vec3 scale;
    for (int a = 0; a < 3; ++a) {
      const double extent = hi[a] - lo[a];
      scale[a] = std::isfinite(extent) && extent > 0.0 ? (kCells - 1) / extent : 0.0;
    }
    std::vector<std::uint32_t> code(n);
    for (std::size_t q = 0; q < n; ++q) {
      const Vec3 p = row3(positions, rows[q]);
      std::uint32_t c = 0;
      for (int a = 0; a < 3; ++a) {
        const double cell = (p[a] - lo[a]) * scale[a];
        const auto k = std::isfinite(cell) ? static_cast<std::uint32_t>(std::clamp(cell, 0.0, kCells - 1.0)) : 0u;
        c |= spread(k) << a;
      }
      code[q] = c;
    }
    order_.resize(n);
    for (std::size_t q = 0; q < n; ++q) order_[q] = static_cast<Index>(q);
    sort_by_code(code);
  }

  std::size_t size() const { return order_.size(); }
  // The i-th index of the order (a q of the rows it was built over).
  Index operator[](std::size_t i) const { return order_[i]; }
  std::size_t memory_bytes() const { return order_.capacity() * sizeof(Index) + sizeof(*this); }

 private:
  static constexpr int kBits = 10;                        // bits per axis of a code (30-bit codes)
  static constexpr double kCells = double(1u << kBits);   // cells per axis

  // Bit i of k moved to bit 3i.
  static std::uint32_t spread(std::uint32_t k) {
    std::uint32_t out = 0;
    for (int i = 0; i < kBits; ++i) out |= ((k >> i) & 1u) << (3 * i);
    return out;
  }
  // order_ sorted by code (stable: a least-significant-digit radix sort, 3 passes of 10 bits).
  void sort_by_code(const std::vector<std::uint32_t>& code) {
    std::vector<Index> tmp(order_.size());
    std::vector<std::uint32_t> count(1u << kBits);
    for (int pass = 0; pass < 3; ++pass) {
      const int shift = pass * kBits;
      std::fill(count.begin(), count.end(), 0u);
      for (Index q : order_) ++count[(code[static_cast<std::size_t>(q)] >> shift) & ((1u << kBits) - 1)];
      std::uint32_t sum = 0;
      for (std::uint32_t& c : count) {
        const std::uint32_t here = c;
        c = sum;
        sum += here;
      }
      for (Index q : order_) tmp[count[(code[static_cast<std::size_t>(q)] >> shift) & ((1u << kBits) - 1)]++] = q;
      order_.swap(tmp);
    }
  }

  IndexList order_;  // #rows: a permutation of 0..#rows-1
};

}  // namespace surfeledit::detail
