// What every driver of a kernel holds per row of the model (internal header): the kernel with its
// references, the deformable rows and one state per row, kept in step with resets, insertions and
// removals. The row detector (row_detector.hpp) and the simplified detector use it alike.
#pragma once

#include <type_traits>

#include "../at_once.hpp"
#include "kernel.hpp"

namespace surfeledit::detail {

// Whether a kernel's seed reads nothing its reset writes (kernel.hpp: kSeedApart).
template <typename Kernel, typename = void>
inline constexpr bool kSeedApart = false;
template <typename Kernel>
inline constexpr bool kSeedApart<Kernel, std::enable_if_t<Kernel::kSeedApart>> = true;

template <typename Kernel>
struct KernelRows {
  using State = typename Kernel::State;

  Kernel kernel;              // the per-point update and its references (zero set, original model)
  IndexList deformable;       // rows with region != Zero, ascending
  RowStates<State> states;    // one per deformable row, indexed by model row

  explicit KernelRows(const CollisionParams& params) : kernel(params) {}

  // Rows and references from the model as it is now, states not yet seeded (default); `zero_rows`
  // gets the zero rows. Throws what Kernel::reset throws (e.g. no zero rows).
  static KernelRows build(const CollisionParams& params, const CollisionScene& scene, int threads,
                          IndexList& zero_rows) {
    KernelRows out(params);
    split_rows(scene, out.deformable, zero_rows);
    out.kernel.reset(scene, out.deformable, zero_rows, threads);
    out.states.assign(static_cast<Index>(scene.regions.size()), out.deformable);
    return out;
  }

  // build() and the states seeded (Kernel::seed). A kernel whose seed reads nothing its reset writes
  // (Kernel::kSeedApart) has the two run at once when that pays (at_once.hpp), each on one thread: the same references
  // and states as one after the other (each is deterministic), in less time.
  static KernelRows build_seeded(const CollisionParams& params, const CollisionScene& scene, int threads) {
    KernelRows out(params);
    IndexList zero_rows;
    split_rows(scene, out.deformable, zero_rows);
    out.states.assign(static_cast<Index>(scene.regions.size()), out.deformable);
    // Without zero rows reset() throws, and the seed does not run.
    const bool apart = kSeedApart<Kernel> && !zero_rows.empty() && at_once_pays(threads, scene.regions.size());
    const int each = apart ? 1 : threads;
    at_once(
        apart, [&] { out.kernel.reset(scene, out.deformable, zero_rows, each); },
        [&] { out.kernel.seed(scene, out.deformable, zero_rows, each, out.states); });
    return out;
  }

  Index rows() const { return static_cast<Index>(states.size()); }

  // Checks the row counts of a step: `scene` and `previous` (#P by 3) have rows() rows.
  void require_step(const CollisionScene& scene, const Points& previous) const {
    require_scene_rows(scene, rows(), "detect");
    if (previous.rows() != rows()) throw Error(ErrorCode::Internal, "previous", "row count differs from the scene");
  }

  // `keep`: one flag per row. Returns the new row of each old row (remap_rows).
  IndexList on_removed(const std::vector<bool>& keep) {
    if (static_cast<Index>(keep.size()) != rows()) throw Error(ErrorCode::Internal, "keep", "row count differs");
    IndexList new_row = remap_rows(keep);
    kernel.on_removed(keep, new_row);
    deformable = remap_list(deformable, keep, new_row);
    states.compact(keep);
    return new_row;
  }

  // Rows appended to `scene`, split from `parents` (deformable rows before the append).
  void on_inserted(const CollisionScene& scene, const IndexList& parents) {
    const Index first = rows(), added = static_cast<Index>(parents.size());
    require_scene_rows(scene, first + added, "on_inserted");
    require_deformable_parents(scene, first, parents);
    split_states(kernel, scene.positions, parents, states);
    for (Index k = 0; k < added; ++k) deformable.push_back(first + k);
    kernel.on_inserted(added);
  }

  std::size_t memory_bytes() const {
    return kernel.memory_bytes() + deformable.capacity() * sizeof(Index) + states.memory_bytes();
  }
};

}  // namespace surfeledit::detail
