// Parameters of a session's edit history and of its response to a colliding step (issue 9 §1, §2;
// docs/algorithms.md §7; thesis ch. 11). Settings rows: response, history_mb, backoff_epsilon,
// backoff_max_iterations (settings.cpp).
#pragma once

#include <cstdint>

#include "surfeledit/core/enum_names.hpp"

namespace surfeledit {

// What a session does with a step that ends with colliding surfels.
enum class Response : std::uint8_t {
  Report = 0,   // keep the step, report the colliding surfels (the default)
  Cancel = 1,   // take the step back (§7 b); the reply still reports what would have collided
  Backoff = 2,  // move the deformable region back until it only touches the zero region (§7 c)
  Merge = 3,    // keep the step and merge the regions with a sharp crease (§7 d; EditSession::merge)
};

constexpr EnumNames<Response, 4> names_of(Response) {
  return {{{Response::Report, "report"},
           {Response::Cancel, "cancel"},
           {Response::Backoff, "backoff"},
           {Response::Merge, "merge"}}};
}
inline const char* to_string(Response r) { return enum_name(r); }

struct ResponseParams {
  Response mode = Response::Report;  // what a colliding step does
  double backoff_epsilon = 0.0;      // back-off stops when the largest depth is below this, model units;
                                     // 0 = 1e-3 of the mean surfel radius
  int backoff_max_iterations = 20;   // back-off stops after this many re-tests, >= 1
};

struct HistoryParams {
  double history_mb = 256.0;  // memory bound of the undo history, MiB; the oldest entries go first (0 = none kept)
};

}  // namespace surfeledit
