// Session settings by name: kind checks, a validated copy, and the listing.
#include "surfeledit/core/settings.hpp"

#include <cmath>
#include <limits>
#include <sstream>

namespace surfeledit {

namespace {

const char* kind_of(const SettingValue& v) {
  if (std::holds_alternative<double>(v)) return "number";
  if (std::holds_alternative<bool>(v)) return "bool";
  return "text";
}

[[noreturn]] void wrong_kind(const NamedSetting& s, const char* expected) {
  throw Error(ErrorCode::InvalidArgument, s.name,
              std::string("expects a ") + expected + ", got a " + kind_of(s.value));
}

double number(const NamedSetting& s) {
  if (!std::holds_alternative<double>(s.value)) wrong_kind(s, "number");
  const double v = std::get<double>(s.value);
  if (!std::isfinite(v)) {
    std::ostringstream msg;
    msg << "must be finite, got " << v;
    throw Error(ErrorCode::InvalidArgument, s.name, msg.str());
  }
  return v;
}

int integer(const NamedSetting& s) {
  if (!std::holds_alternative<double>(s.value)) wrong_kind(s, "integer");
  const double v = std::get<double>(s.value);
  if (!std::isfinite(v) || v != std::floor(v) || v < std::numeric_limits<int>::min() ||
      v > std::numeric_limits<int>::max()) {
    std::ostringstream msg;
    msg.precision(17);
    msg << "expects an integer, got " << v;
    throw Error(ErrorCode::InvalidArgument, s.name, msg.str());
  }
  return static_cast<int>(v);
}

bool flag(const NamedSetting& s) {
  if (!std::holds_alternative<bool>(s.value)) wrong_kind(s, "bool");
  return std::get<bool>(s.value);
}

const std::string& text(const NamedSetting& s) {
  if (!std::holds_alternative<std::string>(s.value)) wrong_kind(s, "text");
  return std::get<std::string>(s.value);
}

}  // namespace

SessionSettings apply_settings(const SessionSettings& current, const std::vector<NamedSetting>& changes) {
  SessionSettings next = current;
  CollisionParams& c = next.collision;
  HierarchyParams& h = next.hierarchy;
  for (const NamedSetting& s : changes) {
    if (s.name == "algorithm") {
      c.algorithm = parse_algorithm(text(s), s.name);
    } else if (s.name == "threshold") {
      c.threshold = number(s);
    } else if (s.name == "boundary") {
      c.boundary = flag(s);
    } else if (s.name == "boundary_n") {
      c.boundary_n = integer(s);
    } else if (s.name == "boundary_i") {
      c.boundary_i = integer(s);
    } else if (s.name == "step_bound") {
      c.step_bound = flag(s);
    } else if (s.name == "sphere_margin") {
      c.sphere_margin = number(s);
    } else if (s.name == "threads") {
      c.threads = integer(s);
    } else if (s.name == "resample") {
      next.resample.enabled = flag(s);
    } else if (s.name == "split_threshold") {
      next.resample.split_threshold = number(s);
    } else if (s.name == "zero_hierarchy") {
      h.zero = parse_zero_hierarchy(text(s), s.name);
    } else if (s.name == "deformable_hierarchy") {
      h.deformable = parse_deformable_hierarchy(text(s), s.name);
    } else if (s.name == "update") {
      h.tree.update = bvh::parse_update(text(s), s.name);
    } else if (s.name == "hybrid_f") {
      h.tree.hybrid_f = number(s);
    } else if (s.name == "sat") {
      h.sat = bvh::parse_sat(text(s), s.name);
    } else if (s.name == "extended") {
      h.extended = flag(s);
    } else if (s.name == "leaf_max_surfels") {
      h.tree.leaf_max_surfels = integer(s);
    } else if (s.name == "leaf_min_surfels") {
      h.tree.leaf_min_surfels = integer(s);
    } else if (s.name == "max_level") {
      h.tree.max_level = integer(s);
    } else if (s.name == "min_leaf_extent") {
      h.tree.min_leaf_extent = number(s);
    } else if (s.name == "inflation") {
      h.tree.inflation = number(s);
    } else if (s.name == "knn_eps") {
      c.knn_eps = number(s);
    } else if (s.name == "simplify") {
      next.simplify.method = parse_simplify_method(text(s), s.name);
    } else if (s.name == "cluster_size") {
      next.simplify.cluster_size = integer(s);
    } else if (s.name == "max_variation") {
      next.simplify.max_variation = number(s);
    } else if (s.name == "member_margin") {
      next.simplify.member_margin = number(s);
    } else {
      throw Error(ErrorCode::InvalidArgument, s.name,
                  "unknown setting '" + s.name +
                      "' (expected algorithm, threshold, boundary, boundary_n, boundary_i, step_bound, sphere_margin, threads, "
                      "resample, split_threshold, zero_hierarchy, deformable_hierarchy, update, hybrid_f, sat, extended, "
                      "leaf_max_surfels, leaf_min_surfels, max_level, min_leaf_extent, inflation, knn_eps, simplify, cluster_size, "
                      "max_variation or member_margin)");
    }
  }
  validate(next.collision);
  validate(next.resample);
  validate(next.hierarchy, next.collision);
  validate(next.simplify);
  // Approximate detection runs the algorithm's own per-surfel test on clusters, without a broad phase.
  if (next.simplify.method != SimplifyMethod::None && c.algorithm != CollisionAlgorithm::None) {
    if (c.algorithm == CollisionAlgorithm::Improved) {
      throw Error(ErrorCode::InvalidArgument, "simplify",
                  std::string("simplify=") + to_string(next.simplify.method) +
                      " cannot run with algorithm=improved (order-dependent spatial coherence); use simple, temporal or "
                      "robust, or simplify=none");
    }
    if (h.any()) {
      throw Error(ErrorCode::InvalidArgument, "simplify",
                  std::string("simplify=") + to_string(next.simplify.method) + " cannot run behind zero_hierarchy=" +
                      to_string(h.zero) + " (approximate detection has no broad phase); set one of them to none");
    }
  }
  return next;
}

std::vector<NamedSetting> describe(const SessionSettings& s) {
  const CollisionParams& c = s.collision;
  const HierarchyParams& h = s.hierarchy;
  return {
      {"algorithm", std::string(to_string(c.algorithm))},
      {"threshold", c.threshold},
      {"boundary", c.boundary},
      {"boundary_n", static_cast<double>(c.boundary_n)},
      {"boundary_i", static_cast<double>(c.boundary_i)},
      {"step_bound", c.step_bound},
      {"sphere_margin", c.sphere_margin},
      {"threads", static_cast<double>(c.threads)},
      {"resample", s.resample.enabled},
      {"split_threshold", s.resample.split_threshold},
      {"zero_hierarchy", std::string(to_string(h.zero))},
      {"deformable_hierarchy", std::string(to_string(h.deformable))},
      {"update", std::string(bvh::to_string(h.tree.update))},
      {"hybrid_f", h.tree.hybrid_f},
      {"sat", std::string(bvh::to_string(h.sat))},
      {"extended", h.extended},
      {"leaf_max_surfels", static_cast<double>(h.tree.leaf_max_surfels)},
      {"leaf_min_surfels", static_cast<double>(h.tree.leaf_min_surfels)},
      {"max_level", static_cast<double>(h.tree.max_level)},
      {"min_leaf_extent", h.tree.min_leaf_extent},
      {"inflation", h.tree.inflation},
      {"knn_eps", c.knn_eps},
      {"simplify", std::string(to_string(s.simplify.method))},
      {"cluster_size", static_cast<double>(s.simplify.cluster_size)},
      {"max_variation", s.simplify.max_variation},
      {"member_margin", s.simplify.member_margin},
  };
}

}  // namespace surfeledit
