// Member definitions of the step journal of Bvh (bvh.hpp, "step journal"): the undo image of bounded steps as
// the nodes they changed. Included by src/bvh/bvh.cpp only.
//
// Why the noted nodes are enough: in a bounded step only step_bounded (every node when refit_all is set),
// refit_leaf and tighten write a node's box, and each also sets its stamp to the step, so a node whose stamp is
// not the current step has not changed in it yet: noting it then keeps its value from before the step. Several
// steps (a back-off re-runs the step within one journal) note a node once per step; putting the notes back in
// reverse leaves each node with its oldest value. Rows, leaves and the inserted lists change only by insertion
// and removal, which end the journal, and a tree with dead slots (whose leaf refits compact them) takes none.
#pragma once

#include <string>
#include <type_traits>

#include "surfeledit/core/bvh/bvh.hpp"
#include "surfeledit/core/types.hpp"

namespace surfeledit::bvh {

template <class Box>
bool Bvh<Box>::start_journal() {
  stop_journal();
  if (!std::is_same_v<Box, Aabb> || !bounded() || dead_ != 0) return false;
  StepImage& j = journal_.image;
  j.step = step_;
  j.shift = shift_;
  j.reach = reach_;
  j.refit_all = refit_all_;
  j.refit_since_build = refit_since_build_;
  j.positions = positions_;
  j.previous = previous_;
  j.radii = radii_;
  journal_.on = true;
  return true;
}

template <class Box>
typename Bvh<Box>::StepImage Bvh<Box>::journal() const {
  if (!journal_.on) throw Error(ErrorCode::Internal, "journal", "the tree keeps no journal");
  StepImage image = journal_.image;
  image.step_after = step_;
  image.node_count = nodes_.size();
  return image;
}

template <class Box>
bool Bvh<Box>::fits(const StepImage& image) const {
  if (image.node_count != nodes_.size() || image.step_after != step_) return false;
  for (const auto& e : image.saved)
    if (e.node < 0 || static_cast<std::size_t>(e.node) >= nodes_.size()) return false;
  return true;
}

template <class Box>
void Bvh<Box>::restore(const StepImage& image) {
  if (!fits(image)) {
    throw Error(ErrorCode::Internal, "journal",
                "tree image of step " + std::to_string(image.step_after) + " over " +
                    std::to_string(image.node_count) + " nodes does not fit a tree at step " + std::to_string(step_) +
                    " over " + std::to_string(nodes_.size()));
  }
  put_back(image);
}

template <class Box>
void Bvh<Box>::restore_journal() {
  if (!journal_.on) throw Error(ErrorCode::Internal, "journal", "the tree keeps no journal");
  put_back(journal_.image);
}

template <class Box>
void Bvh<Box>::put_back(const StepImage& image) {
  for (auto e = image.saved.rbegin(); e != image.saved.rend(); ++e) {
    const std::size_t k = static_cast<std::size_t>(e->node);
    nodes_[k].box = e->box;
    stamp_[k] = e->stamp;
    since_[k] = e->since;
  }
  step_ = image.step;
  shift_ = image.shift;
  reach_ = image.reach;
  refit_all_ = image.refit_all;
  refit_since_build_ = image.refit_since_build;
  positions_ = image.positions;
  previous_ = image.previous;
  radii_ = image.radii;
}

}  // namespace surfeledit::bvh
