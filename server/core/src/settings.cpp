// Session settings by name: the table (one row per setting), the checks every row gets from its
// kind and range, a validated copy, and the listing.
#include "surfeledit/core/settings.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <sstream>
#include <type_traits>
#include <utility>

#include "surfeledit/core/util.hpp"

namespace surfeledit {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Accepted range of a Number/Integer row.
struct Range {
  double min = -kInf;     // smallest accepted value
  double max = kInf;      // largest accepted value
  bool min_open = false;  // min itself refused
};
Range at_least(double lo) { return {lo, kInf, false}; }
Range within(double lo, double hi) { return {lo, hi, false}; }
Range above(double lo, double hi) { return {lo, hi, true}; }  // lo itself refused

// Upper bounds of the settings that size allocations, thread teams or loops (docs/hardening.md), so that
// no client number becomes an unbounded one.
constexpr double kMaxNeighbours = 256;          // boundary_n, boundary_i: kNN columns per surfel
constexpr double kMaxLeafSurfels = 1 << 20;     // leaf sizes and cluster_size
constexpr double kMaxFactor = 1e6;              // dimensionless multipliers (margins, split ratio, knn_eps)
constexpr double kMaxHistoryMb = 1 << 20;       // 1 TiB: beyond any machine, far below overflow
constexpr double kMaxBackoffIterations = 1000;  // back-off re-tests per step
constexpr double kMaxBlendNeighbourFactor = 16;  // blend neighbourhood radius in mean radii (~800 neighbours)
// threads: 0 (all) up to hardware_threads() (more only oversubscribes; 2^31 made libgomp abort).

// The member of SessionSettings reached through the data-member pointers `Path`.
template <auto... Path>
auto& member(SessionSettings& s) {
  return (s .* ... .* Path);
}
template <auto... Path>
const auto& member(const SessionSettings& s) {
  return (s .* ... .* Path);
}

template <typename T>
constexpr SettingType kind_of() {
  if constexpr (std::is_enum_v<T>) return SettingType::Text;
  else if constexpr (std::is_same_v<T, bool>) return SettingType::Bool;
  else if constexpr (std::is_same_v<T, int>) return SettingType::Integer;
  else {
    static_assert(std::is_same_v<T, double>, "a setting is an enum, bool, int or double");
    return SettingType::Number;
  }
}

// One row: the setting `name` stored at SessionSettings.*Path; kind and choices follow its type.
template <auto... Path>
SettingSpec row(const char* name, const char* doc, Range range = {}) {
  using T = std::decay_t<decltype(member<Path...>(std::declval<SessionSettings&>()))>;
  SettingSpec spec{name, kind_of<T>(), doc, range.min, range.max, range.min_open, {}, nullptr, nullptr};
  if constexpr (std::is_enum_v<T>) {
    for (const EnumName<T>& n : enum_names<T>()) spec.choices.push_back(n.name);
  }
  spec.get = [](const SessionSettings& s) -> SettingValue {
    const T& v = member<Path...>(s);
    if constexpr (std::is_enum_v<T>) return std::string(enum_name(v));
    else if constexpr (std::is_same_v<T, int>) return std::int64_t{v};
    else return v;
  };
  spec.set = [](SessionSettings& s, const SettingValue& v) {
    T& m = member<Path...>(s);
    if constexpr (std::is_enum_v<T>) m = parse_enum<T>(std::get<std::string>(v), "");
    else if constexpr (std::is_same_v<T, int>) m = static_cast<int>(std::get<std::int64_t>(v));
    else m = std::get<T>(v);
  };
  return spec;
}

using S = SessionSettings;
using C = CollisionParams;
using H = HierarchyParams;
using R = ResampleParams;
using B = bvh::BvhParams;
using P = SimplifyParams;
using E = ResponseParams;
using Y = HistoryParams;
using L = BlendSettings;

std::vector<SettingSpec> make_table() {
  return {
      row<&S::collision, &C::algorithm>("algorithm", "collision detector (docs/algorithms.md §4)"),
      row<&S::collision, &C::threshold>("threshold", "W of the inside test (p1 - p2) . n2 < W, model units"),
      row<&S::collision, &C::boundary>("boundary", "boundary-surfel heuristic (simple/improved/temporal)"),
      row<&S::collision, &C::boundary_n>("boundary_n", "neighbours looked at for boundary marks", within(1, kMaxNeighbours)),
      row<&S::collision, &C::boundary_i>("boundary_i", "of those, the nearest zero surfels marked boundary "
                                                       "(<= boundary_n)", within(1, kMaxNeighbours)),
      row<&S::collision, &C::step_bound>("step_bound", "per-surfel step bound (simple/improved/temporal)"),
      row<&S::collision, &C::sphere_margin>("sphere_margin", "temporal/robust spheres shrink by this many radii "
                                                             "of the nearest surfel", within(0, kMaxFactor)),
      row<&S::collision, &C::threads>("threads", "worker threads for detection (0 = all, at most the hardware threads; "
                                                   "a new tool starts with its session's)",
                                      within(0, hardware_threads())),
      row<&S::collision, &C::parallel_min_ms>("parallel_min_ms", "a detection step runs on several threads only "
                                              "when its estimated one-thread work is at least this, ms (0 = always)",
                                              within(0, 1e6)),
      row<&S::resample, &R::enabled>("resample", "dynamic resampling of stretched surfels"),
      row<&S::resample, &R::split_threshold>("split_threshold", "stretch ratio that splits a surfel", Range{1, kMaxFactor, true}),
      row<&S::hierarchy, &H::zero>("zero_hierarchy", "tree over the zero region (sphere_* = sphere cluster trees)"),
      row<&S::hierarchy, &H::deformable>("deformable_hierarchy", "tree over the deformable region "
                                                                 "(needs zero_hierarchy)"),
      row<&S::hierarchy, &H::tree, &B::update>("update", "refit of the deformable tree"),
      row<&S::hierarchy, &H::tree, &B::hybrid_f>("hybrid_f", "hybrid: fraction of the levels refit bottom-up",
                                                 within(0, 1)),
      row<&S::hierarchy, &H::sat>("sat", "OBB/AABB overlap test"),
      row<&S::hierarchy, &H::extended>("extended", "narrow phase against the original model (needs robust)"),
      row<&S::hierarchy, &H::tree, &B::leaf_max_surfels>("leaf_max_surfels", "a tree node with at most this many "
                                                         "surfels is a leaf (>= leaf_min_surfels)", within(1, kMaxLeafSurfels)),
      row<&S::hierarchy, &H::tree, &B::leaf_min_surfels>("leaf_min_surfels", "no split leaves a child with fewer "
                                                         "surfels", within(1, kMaxLeafSurfels)),
      row<&S::hierarchy, &H::tree, &B::max_level>("max_level", "deepest tree level (root = 0)", within(0, 64)),
      row<&S::hierarchy, &H::tree, &B::min_leaf_extent>("min_leaf_extent", "leaf boxes at least this wide per "
                                                        "axis, model units", at_least(0)),
      row<&S::hierarchy, &H::tree, &B::inflation>("inflation", "margin added to a box when a refit recomputes "
                                                  "it, model units", at_least(0)),
      row<&S::collision, &C::knn_eps>("knn_eps", "approximate nearest-surfel search (0 = exact)", within(0, kMaxFactor)),
      row<&S::simplify, &P::method>("simplify", "approximate detection on clusters of the deformable region "
                                                "(simple/temporal/robust, no hierarchy)"),
      row<&S::simplify, &P::cluster_size>("cluster_size", "surfels per cluster (1 = the exact result); also the "
                                                          "leaves of sphere_* trees", within(1, kMaxLeafSurfels)),
      row<&S::simplify, &P::max_variation>("max_variation", "largest surface variation of a cluster; also for "
                                                            "sphere_* trees", within(0, 1)),
      row<&S::simplify, &P::member_margin>("member_margin", "approximate detection: members tested within this "
                                                            "many cluster radii of the zero region", within(0, kMaxFactor)),
      row<&S::response, &E::mode>("response", "what a colliding step does: report it, cancel the step, back off "
                                              "until the regions only touch, or merge the regions "
                                              "(docs/algorithms.md §7)"),
      row<&S::history, &Y::history_mb>("history_mb", "memory bound of the undo history, MiB (oldest entries "
                                                     "dropped first)", within(0, kMaxHistoryMb)),
      row<&S::response, &E::backoff_epsilon>("backoff_epsilon", "back-off stops below this largest depth, model "
                                                                "units (0 = 1e-3 of the mean surfel radius)",
                                             at_least(0)),
      row<&S::response, &E::backoff_max_iterations>("backoff_max_iterations", "back-off stops after this many "
                                                                              "re-tests", within(1, kMaxBackoffIterations)),
      row<&S::collision, &C::inside>("inside", "temporal/robust inside test: nearest surfel (thesis), winding "
                                               "number of the zero region, or k-nearest vote (docs/algorithms.md "
                                               "§4.6)"),
      row<&S::collision, &C::winding_beta>("winding_beta", "winding: far-field acceptance of the dipole tree "
                                                           "(0 = exact sums)", within(0, 100)),
      row<&S::collision, &C::vote_k>("vote_k", "vote: zero surfels that vote", within(1, 256)),
      row<&S::collision, &C::swept>("swept", "temporal/robust: report points whose step passed through the "
                                             "rigid solid (no tunnelling, docs/algorithms.md §4.7)"),
      row<&S::blend, &L::neighbour_factor>("blend_neighbour_factor", "blend: particle neighbourhood radius, "
                                                                     "in mean surfel radii (§12.3.3)", above(0, kMaxBlendNeighbourFactor)),
      row<&S::blend, &L::gamma>("blend_gamma", "blend: region scaling exponent (Eq. 12.28)", within(0, 100)),
      row<&S::blend, &L::open_region>("blend_open_region", "blend after a boolean (open region, §12.4.1): the "
                                                           "requested repulsion, an attracting spring, or none"),
      row<&S::blend, &L::spring_r0>("blend_spring_r0", "blend: equilibrium distance of that spring, mean surfel "
                                                       "radii", above(0, kMaxFactor)),
  };
}

// Shortest text that reads back as `v`.
std::string show(double v) {
  std::ostringstream out;
  for (int precision = 6; precision <= 17; ++precision) {
    out.str("");
    out.precision(precision);
    out << v;
    if (!std::isfinite(v) || std::strtod(out.str().c_str(), nullptr) == v) break;
  }
  return out.str();
}

std::string show(const SettingValue& v) {
  if (const double* d = std::get_if<double>(&v)) return show(*d);
  if (const std::int64_t* i = std::get_if<std::int64_t>(&v)) return std::to_string(*i);
  if (const bool* b = std::get_if<bool>(&v)) return *b ? "true" : "false";
  return "'" + std::get<std::string>(v) + "'";
}

std::string join(const std::vector<const char*>& names) {
  std::string out;
  for (const char* n : names) out += (out.empty() ? "" : ", ") + std::string(n);
  return out;
}

[[noreturn]] void refuse(const SettingSpec& spec, const SettingValue& got) {
  throw Error(ErrorCode::InvalidArgument, spec.name, "expects " + expected_value(spec) + ", got " + show(got));
}

bool in_range(const SettingSpec& spec, double v) {
  return std::isfinite(v) && (spec.min_open ? v > spec.min : v >= spec.min) && v <= spec.max;
}

// `v` as a value of spec's kind, or InvalidArgument naming the setting.
SettingValue check_setting(const SettingSpec& spec, const SettingValue& v) {
  const double* d = std::get_if<double>(&v);
  const std::int64_t* i = std::get_if<std::int64_t>(&v);
  switch (spec.kind) {
    case SettingType::Number:
      if (!d && !i) refuse(spec, v);
      if (!in_range(spec, d ? *d : static_cast<double>(*i))) refuse(spec, v);
      return d ? *d : static_cast<double>(*i);
    case SettingType::Integer: {
      if (!d && !i) refuse(spec, v);
      const double x = d ? *d : static_cast<double>(*i);
      if (x != std::floor(x) || !in_range(spec, x) || x < std::numeric_limits<int>::min() ||
          x > std::numeric_limits<int>::max()) {
        refuse(spec, v);
      }
      return static_cast<std::int64_t>(x);
    }
    case SettingType::Bool:
      if (!std::holds_alternative<bool>(v)) refuse(spec, v);
      return v;
    case SettingType::Text: {
      const std::string* text = std::get_if<std::string>(&v);
      if (!text) refuse(spec, v);
      for (const char* c : spec.choices)
        if (*text == c) return v;
      throw_unknown_name(spec.name, *text, join(spec.choices));
    }
  }
  refuse(spec, v);
}

const SettingSpec& find_spec(const std::string& name) {
  for (const SettingSpec& spec : setting_specs())
    if (name == spec.name) return spec;
  std::vector<const char*> known;
  for (const SettingSpec& spec : setting_specs()) known.push_back(spec.name);
  throw Error(ErrorCode::InvalidArgument, name, "unknown setting '" + name + "'; known: " + join(known));
}

// The checks that involve more than one setting, after every change is applied.
void validate_combination(const SessionSettings& s) {
  validate(s.collision);  // boundary_i <= boundary_n
  validate(s.resample);
  validate(s.hierarchy, s.collision);  // leaf sizes, deformable needs zero, extended needs robust, ...
  validate(s.simplify);
  // Approximate detection runs the algorithm's own per-surfel test on clusters, without a broad phase.
  const CollisionAlgorithm algorithm = s.collision.algorithm;
  if (s.simplify.method == SimplifyMethod::None || algorithm == CollisionAlgorithm::None) return;
  if (algorithm == CollisionAlgorithm::Improved) {
    throw Error(ErrorCode::InvalidArgument, "simplify",
                std::string("simplify=") + to_string(s.simplify.method) +
                    " cannot run with algorithm=improved (order-dependent spatial coherence); use simple, temporal or "
                    "robust, or simplify=none");
  }
  if (s.hierarchy.any()) {
    throw Error(ErrorCode::InvalidArgument, "simplify",
                std::string("simplify=") + to_string(s.simplify.method) + " cannot run behind zero_hierarchy=" +
                    to_string(s.hierarchy.zero) + " (approximate detection has no broad phase); set one of them to none");
  }
}

}  // namespace

const std::vector<SettingSpec>& setting_specs() {
  static const std::vector<SettingSpec> table = make_table();
  return table;
}

SettingValue default_value(const SettingSpec& spec) { return spec.get(SessionSettings{}); }

std::string expected_value(const SettingSpec& spec) {
  if (spec.kind == SettingType::Bool) return "a bool";
  if (spec.kind == SettingType::Text) return "one of " + join(spec.choices);
  std::string out = spec.kind == SettingType::Integer ? "an integer" : "a finite number";
  const bool lo = std::isfinite(spec.min), hi = std::isfinite(spec.max);
  if (lo && hi) return out + " in " + (spec.min_open ? "(" : "[") + show(spec.min) + ", " + show(spec.max) + "]";
  if (lo) return out + (spec.min_open ? " > " : " >= ") + show(spec.min);
  if (hi) return out + " <= " + show(spec.max);
  return out;
}

SessionSettings apply_settings(const SessionSettings& current, const std::vector<NamedSetting>& changes) {
  SessionSettings next = current;
  for (const NamedSetting& change : changes) {
    const SettingSpec& spec = find_spec(change.name);
    spec.set(next, check_setting(spec, change.value));
  }
  validate_combination(next);
  return next;
}

std::vector<NamedSetting> describe(const SessionSettings& settings) {
  std::vector<NamedSetting> out;
  out.reserve(setting_specs().size());
  for (const SettingSpec& spec : setting_specs()) out.push_back({spec.name, spec.get(settings)});
  return out;
}

}  // namespace surfeledit
