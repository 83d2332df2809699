// The hierarchical detector's undo images and deep copies (hierarchical_detector.hpp).
#include "hierarchical_detector.hpp"

namespace surfeledit::detail {

std::shared_ptr<HierarchicalDetector::Image> HierarchicalDetector::image_but_narrow(bool tree) const {
  auto image = std::make_shared<Image>();
  if (def_ && tree) image->def = std::make_shared<const bvh::Bvh<bvh::Aabb>>(*def_);
  if (bounded_) {
    // The radii the next shift compares with.
    if (tree) image->reach = std::make_shared<const std::vector<double>>(prev_radius_);
  } else {
    auto reach = std::make_shared<std::vector<double>>();
    reach->reserve(deformable_.size());
    for (Index r : deformable_) reach->push_back(reach_[r]);
    image->reach = std::move(reach);
  }
  image->rows = rows_;
  image->step = step_;
  image->evaluations = evaluations_;
  image->inserted_nu = inserted_nu_;
  image->rebuilds_adopted = rebuilds_adopted_;
  return image;
}

std::shared_ptr<const DetectorImage> HierarchicalDetector::save_image(const IndexList*) const {
  auto image = image_but_narrow();
  if (extended_) {
    image->extended = std::make_shared<const bvh::ExtendedNarrow>(*extended_);
  } else {
    image->narrow = narrow_->save_image(nullptr);
    if (!image->narrow) return nullptr;
  }
  return image;
}

void HierarchicalDetector::restore_image(const DetectorImage& image) {
  const auto* mine = dynamic_cast<const Image*>(&image);
  if (!mine || !mine->extended != !extended_ || !fits(*mine)) {
    throw Error(ErrorCode::Internal, "history", "detector image does not fit this hierarchical detector");
  }
  if (extended_) *extended_ = *mine->extended;
  else narrow_->restore_image(*mine->narrow);  // checks its own part before it changes anything
  restore_but_narrow(*mine);
}

bool HierarchicalDetector::fits(const Image& image, bool tree) const {
  if (image.rows != rows_) return false;
  if (image.reach ? image.reach->size() != deformable_.size() : !(bounded_ && image.journal)) return false;
  if (!tree) return !def_journal_ || def_->journaling();
  if (!def_) return !image.def && !image.def_steps;
  return image.def || (image.def_steps && def_->fits(*image.def_steps));
}

void HierarchicalDetector::restore_but_narrow(const Image& image) {
  if (image.def) {
    *def_ = *image.def;  // with the journal it held when copied (one taken within this journal goes on)
    if (!def_journal_) def_->stop_journal();
  } else if (image.def_steps) {
    def_->restore(*image.def_steps);
  }
  // The filter is not in the image: its boxes are fit afresh at the next step (from that step's rows).
  if (filter_) filter_->refit_all_next_step();
  if (image.reach) {
    const std::vector<double>& reach = *image.reach;
    if (bounded_) prev_radius_ = reach;
    else for (std::size_t q = 0; q < deformable_.size(); ++q) reach_[deformable_[q]] = reach[q];
  }
  step_ = image.step;
  evaluations_ = image.evaluations;
  inserted_nu_ = image.inserted_nu;
  rebuilds_adopted_ = image.rebuilds_adopted;
}

bool HierarchicalDetector::start_journal() {
  drop_journal();
  if (extended_ || !narrow_->start_journal()) return false;
  def_journal_ = def_ && def_->start_journal();
  // Bounded, with no tree or a journaled one: neither the tree nor the radii are copied now.
  auto start = image_but_narrow(!(bounded_ && (!def_ || def_journal_)));
  start->journal = true;
  journal_ = std::move(start);
  return true;
}

std::shared_ptr<const DetectorImage> HierarchicalDetector::journal_image() const {
  if (!journal_ || !fits(*journal_, false)) return nullptr;
  auto narrow = narrow_->journal_image();
  if (!narrow) return nullptr;
  auto image = std::make_shared<Image>(*journal_);  // shares the journal's tree copy and reach
  image->narrow = std::move(narrow);
  if (journal_def_) image->def = journal_def_;
  else if (def_journal_) image->def_steps = std::make_shared<const bvh::Bvh<bvh::Aabb>::StepImage>(def_->journal());
  if (journal_reach_) image->reach = journal_reach_;
  return image;
}

void HierarchicalDetector::restore_journal() {
  if (!journal_ || !fits(*journal_, false)) throw Error(ErrorCode::Internal, "history", "no journal to restore");
  narrow_->restore_journal();
  if (journal_def_) *def_ = *journal_def_;
  else if (def_journal_) def_->restore_journal();
  restore_but_narrow(*journal_);
  if (journal_reach_) prev_radius_ = *journal_reach_;
}

void HierarchicalDetector::stop_journal() {
  if (!extended_) narrow_->stop_journal();
  drop_journal();
}

void HierarchicalDetector::drop_journal() {
  if (def_) def_->stop_journal();
  journal_.reset();
  def_journal_ = false;
  journal_def_.reset();
  journal_reach_.reset();
}

void HierarchicalDetector::keep_journal_reach() {
  if (journal_ && !journal_->reach && !journal_reach_)
    journal_reach_ = std::make_shared<const std::vector<double>>(prev_radius_);
}

void HierarchicalDetector::keep_journal_tree() {
  if (!def_journal_) return;
  def_->restore_journal();
  def_->stop_journal();
  journal_def_ = std::move(def_);
  def_journal_ = false;
}

std::unique_ptr<CollisionDetector> HierarchicalDetector::clone() const {
  std::unique_ptr<CollisionDetector> narrow = narrow_->clone();
  if (!narrow) return nullptr;
  auto out = std::make_unique<HierarchicalDetector>(
      params_, h_, std::unique_ptr<NarrowDetector>(static_cast<NarrowDetector*>(narrow.release())));
  if (extended_) out->extended_ = std::make_unique<bvh::ExtendedNarrow>(*extended_);
  out->extended_bytes_ = extended_bytes_;
  out->zero_ = zero_;
  if (def_) {
    out->def_ = std::make_unique<bvh::Bvh<bvh::Aabb>>(*def_);
    out->def_->stop_journal();  // the copy keeps no journal
  }
  if (filter_) out->filter_ = std::make_unique<bvh::Bvh<bvh::Aabb>>(*filter_);
  out->zero_hull_ = zero_hull_;
  out->deformable_ = deformable_;
  out->rows_ = rows_;
  out->reach_ = reach_;
  out->bounded_ = bounded_;
  out->zero_bounds_ = zero_bounds_;
  out->prev_radius_ = prev_radius_;
  out->candidate_ = candidate_;
  out->marked_ = marked_;
  out->topology_ = topology_;
  out->step_ = step_;
  out->evaluations_ = evaluations_;
  out->inserted_nu_ = inserted_nu_;
  out->preprocess_ms_ = preprocess_ms_;
  out->zero_build_ms_ = zero_build_ms_;
  out->def_build_ms_ = def_build_ms_;
  out->last_rebuild_ms_ = last_rebuild_ms_;
  out->rebuilds_adopted_ = rebuilds_adopted_;
  return out;
}

}  // namespace surfeledit::detail
