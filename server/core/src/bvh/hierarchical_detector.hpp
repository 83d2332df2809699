// Collision detection with bounding volume hierarchies (docs/algorithms.md §5, thesis ch. 7-8): a broad
// phase over a zero tree (AABB, OBB or sphere boxes, one std::visit per step) and optionally a
// deformable AABB tree, in front of the configured algorithm's narrow test (collision_detail.hpp:
// NarrowDetector, the same code as without a hierarchy) or of the extended narrow phase. Not a public
// header: the session gets the detector through make_hierarchical_detector (collision_detail.hpp).
//
// Broad phase. Each deformable surfel is bounded by the ball (p, r + |t|): its radius grown by its
// own displacement t this step, so the ball covers the whole path of its disc during the step. The
// zero tree bounds the balls (p2, r2) of the zero surfels. A surfel is a candidate when
//  - surfel/tree (no deformable tree): its ball overlaps a zero leaf box (Code 7.6);
//  - tree/tree: it lies in a deformable leaf whose box (refit each step over those balls, update =
//    bottom_up | top_down | hybrid; or, bounded, its last fit grown by the steps' largest displacement and
//    refit when it reaches a zero leaf, docs/algorithms.md §5) overlaps a zero leaf box (Code 8.4).
// Larger balls or boxes only add candidates: surfel/tree takes (p, r + the step's largest |t|).
// A non-candidate's ball misses every zero surfel ball: |p - p2| > r + |t| + r2 for all zero surfels,
// which is the step bound of §4.1, so Simple leaves its state unchanged -- the same colliding set
// as without a hierarchy, by construction. Temporal needs the nearest zero distance of every surfel
// that leaves its sphere anyway (for the next sphere), so it ignores the candidates and is exactly
// Temporal: detect() skips the broad phase for it. Robust has no step bound; a non-candidate did not
// come within its step of the zero surface, so its parity cannot have changed by crossing it (its
// inside state is re-derived once it is a candidate again, see RobustKernel::not_candidate in
// collision/robust_kernel.hpp); the tests check the equality on every step of the scenario scenes. Not equal:
// a classification that flips far from every surface, which only the detector without a tree counts
// (docs/algorithms.md §4.4, "far-field flips").
//
// Robust with `inside` = winding | vote or `swept`: the inside state also changes across the caps of the zero region's
// open boundary (where the deformable part is attached), far from every zero surfel; a row whose ball (p, r + |t|)
// reaches one of the boundary's balls (NarrowDetector::open_boundary) is a candidate too (one pass over the
// deformable rows per step, only when there are such balls).
//
// The idle step (docs/algorithms.md §5): a displacement bound in the detect input replaces the pass for the
// step's largest displacement (shift_of); surfel/tree tests only the rows of a bounded filter tree's leaves
// that reach the box of all zero balls (surfel_tree); tree/tree with OBB or sphere zero trees prunes
// deformable boxes missing that box too.
//
// Rebuild on idle (thesis §8.3.3): start_rebuild() builds a fresh deformable tree on a background
// thread (bvh::BvhRebuilder); detect() adopts it at its start when it is finished and the rows were
// neither inserted nor removed meanwhile (topology tag), then refits it as usual. No step waits.
//
// The class is defined in hierarchical_detector.cpp (reset, detect, row changes, reports) and
// hierarchical_detector_image.cpp (undo images and copies).
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "../collision_detail.hpp"
#include "step_shift.hpp"
#include "surfeledit/core/bvh/bvh.hpp"
#include "surfeledit/core/bvh/extended.hpp"
#include "surfeledit/core/bvh/rebuilder.hpp"
#include "zero_tree.hpp"

namespace surfeledit::detail {

class HierarchicalDetector final : public CollisionDetector {
 public:
  HierarchicalDetector(const CollisionParams& params, const HierarchyParams& h, std::unique_ptr<NarrowDetector> narrow)
      : CollisionDetector(params), h_(h), narrow_(std::move(narrow)) {}

  void reset(const CollisionScene& scene) override;
  CollisionResult detect(const CollisionScene& scene, const Points& previous) override;
  void on_removed(const std::vector<bool>& keep) override;
  void on_inserted(const CollisionScene& scene, const IndexList& parents) override;
  // The narrow phase's (none with the extended narrow phase).
  ResetRows reset_rows() const override { return extended_ ? ResetRows{} : narrow_->reset_rows(); }
  std::size_t memory_bytes() const override;
  std::vector<std::pair<std::string, std::size_t>> structures() const override;
  bool start_rebuild(const CollisionScene& scene) override;
  HierarchyInfo hierarchy_info() const override;

  // Undo (history.hpp). A step changes the narrow phase's states (or the extended narrow phase), the
  // deformable tree (refit, adopted rebuilds), the balls' reach and the step counters; the zero tree
  // changes only at reset, removal and insertion. The broad phase does not restrict detect_only(), so an
  // image always holds every deformable row (`rows` is ignored).
  std::shared_ptr<const DetectorImage> save_image(const IndexList*) const override;
  void restore_image(const DetectorImage& image) override;
  // A deep copy (trees included); a background rebuild under way is not copied.
  std::unique_ptr<CollisionDetector> clone() const override;
  // The journal: the narrow phase's (the states its sweeps change), beside the rest of an image -- the
  // counters and, when the step may change them, the reach -- taken when it starts. A bounded deformable tree
  // keeps a journal of the nodes its steps change (bvh.hpp, step journal), so a step's image holds those
  // rather than a copy of the tree; other trees are copied when the journal starts, and a rebuilt tree adopted
  // meanwhile takes the old one, put back as it was at the start, into the image. None with the extended narrow
  // phase, nor when the narrow phase keeps no states this time (save_image() then). It tells no tested rows
  // (journal_tested() false: a back-off re-detects its kept fraction whole): a row outside the broad phase may
  // leave its sphere without a query.
  bool start_journal() override;
  std::shared_ptr<const DetectorImage> journal_image() const override;
  void restore_journal() override;
  void stop_journal() override;

 private:
  // What detect() changes (save_image / restore_image); trees and the extended state are copies.
  struct Image final : DetectorImage {
    std::shared_ptr<const DetectorImage> narrow;             // narrow phase's image (without extended)
    std::shared_ptr<const bvh::ExtendedNarrow> extended;     // extended narrow phase (with it)
    // The deformable tree (with one): a copy, or (journal images of a bounded tree) the nodes the steps changed.
    std::shared_ptr<const bvh::Bvh<bvh::Aabb>> def;
    std::shared_ptr<const bvh::Bvh<bvh::Aabb>::StepImage> def_steps;
    // Per deformable row (bounded: its radius); shared, so the journal's image hands it over without a copy.
    // Null in a journal image of bounded steps that changed no radius (the deformation step's bound says so).
    std::shared_ptr<const std::vector<double>> reach;
    // A journal's image (start_journal / journal_image): the only kind whose bounded reach may be null.
    bool journal = false;
    Index rows = 0;
    std::int64_t step = 0, evaluations = 0;
    Index inserted_nu = 0, rebuilds_adopted = 0;
    std::size_t bytes() const override {
      return sizeof(*this) + (narrow ? narrow->bytes() : 0) + (def ? def->memory_bytes() : 0) +
             (def_steps ? def_steps->bytes() : 0) +
             (reach ? reach->capacity() * sizeof(double) : 0) +
             (extended ? extended->colliding().capacity() * (1 + 2 * sizeof(std::int64_t)) : 0);
    }
  };

  // An image without the narrow phase's part (`narrow`, `extended` null; `tree` false: nor the deformable tree,
  // nor a bounded reach); whether an image's part fits this detector's rows and tree (`tree` false: but the
  // tree's); that part put back (once it fits).
  std::shared_ptr<Image> image_but_narrow(bool tree = true) const;
  bool fits(const Image& image, bool tree = true) const;
  void restore_but_narrow(const Image& image);
  // Ends the journal's own part (reset, removal, insertion, stop_journal). While one runs: prev_radius_ is kept
  // before a step may change it (keep_journal_reach), and def_, put back as it was at the start, becomes the
  // journal's tree before a rebuilt tree replaces it (keep_journal_tree; def_ is null after it).
  void drop_journal();
  void keep_journal_reach();
  void keep_journal_tree();

  // Surfel/tree: marks the candidates among the deformable rows, each ball (p, r + reach) tested against
  // zero_bounds_ and then down the zero tree; only the rows in filter_'s leaves that reach zero_hull_.
  Index surfel_tree(const CollisionScene& scene, const Points& previous, bvh::BvhCounters& counters);
  // Marks the rows (not yet candidates) whose ball (p, r + |t|) reaches a ball of the narrow phase's open boundary;
  // returns how many.
  Index near_open_boundary(const CollisionScene& scene, const Points& previous);
  // The step's shift and reach (step_shift.hpp): the scene's displacement bound when it has one (validated;
  // checked against the measured values in a debug build), else measured.
  StepShift shift_of(const CollisionScene& scene, const Points& previous);
  // Swaps in a finished background rebuild (never waits); dropped when rows changed since it started.
  void adopt_rebuilt_tree();

  HierarchyParams h_;
  std::unique_ptr<NarrowDetector> narrow_;          // the algorithm's test (unused with extended)
  std::unique_ptr<bvh::ExtendedNarrow> extended_;   // extended narrow phase (extended = true)
  std::size_t extended_bytes_ = 0;                  // estimate of what extended_ holds
  ZeroTree zero_;                                   // over the zero rows; never refit (zero surfels do not move)
  std::unique_ptr<bvh::Bvh<bvh::Aabb>> def_;        // over the deformable rows (deformable_hierarchy = aabb)
  bvh::BvhRebuilder<bvh::Aabb> rebuilder_;          // background rebuild of def_
  IndexList deformable_;                            // rows with region != Zero, ascending
  Index rows_ = 0;                                  // rows of the model the state refers to
  Values reach_;                                    // #P: radius + own displacement this step (!bounded_)
  bool bounded_ = false;                            // no reach_: def_ uses the bounded update, or there is no def_
  bvh::Aabb zero_bounds_;                           // box of every zero ball (surfel/tree's first test)
  std::unique_ptr<bvh::Bvh<bvh::Aabb>> filter_;     // surfel/tree: bounded tree over the deformable rows, whose
                                                    // leaves reaching zero_hull_ hold every row to test
  bvh::Bvh<bvh::Aabb> zero_hull_;                   // surfel/tree: one leaf, the box zero_bounds_
  std::vector<double> prev_radius_;                 // bounded: by deformable_ index, its radius at the last step
  std::vector<std::uint8_t> candidate_;             // #P: 1 = candidate this step
  IndexList marked_;                                // the rows candidate_ holds set (cleared at the next step)
  std::vector<std::int32_t> fifo_;                  // scratch of the surfel/tree queue
  std::uint64_t topology_ = 0;                      // bumped by reset, insertions and removals
  std::int64_t step_ = 0;                           // steps of the extended narrow phase
  std::int64_t evaluations_ = 0;                    // extended evaluations counted so far
  Index inserted_nu_ = 0;                           // boxes grown by insertions (reported with the next step)
  double preprocess_ms_ = 0.0;                      // whole reset: narrow phase and trees
  double zero_build_ms_ = 0.0;                      // build of the zero tree
  double def_build_ms_ = 0.0;                       // build of the deformable tree
  double last_rebuild_ms_ = 0.0;                    // the last finished background rebuild
  Index rebuilds_adopted_ = 0;                      // background rebuilds swapped in since the reset
  std::shared_ptr<const Image> journal_;            // while a journal keeps states: image_but_narrow() at its start
  bool def_journal_ = false;                        // def_ keeps the journal's changes (a bounded tree)
  std::shared_ptr<const bvh::Bvh<bvh::Aabb>> journal_def_;  // the journal's start tree, when a rebuild replaced it
  std::shared_ptr<const std::vector<double>> journal_reach_;  // bounded: prev_radius_ before a step changed it
};

}  // namespace surfeledit::detail
