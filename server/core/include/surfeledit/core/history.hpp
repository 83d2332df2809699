// A session's edit history (issue 9 §1): one entry per accepted change, enough to restore the state
// before it bit for bit (undo) and after it (redo).
//
// An entry holds one image of the session: the state *before* its op while the op is applied, the
// state *after* it once undone (undo and redo swap the live state with the stored image, so each
// entry keeps one side at a time). Two kinds of image:
//  - Rows: a step that neither inserted nor removed rows: the rows it moved (positions, normals,
//    tangents, per-row versions as runs) and the detector's per-row states (DetectorImage) -- for row
//    detectors only the states the step changed (the detector's journal); buffers of dropped entries
//    are reused. A step whose response merges upgrades its image to a whole one then;
//  - Tool: a change of the acting tool alone (set_regions, configure, release): that tool's state and
//    the session's history bound, nothing model-sized (ToolOnlyImage). Its detector is not kept when
//    it is exactly what a reset from the model as it is then makes (ToolImage::derive_detector);
//  - Whole: every other change (load, remove, merge, a step with resampling, ...): the whole model and
//    every tool (tool.hpp: regions and fields, settings, and the detector object itself: the live one
//    after a change that replaced it, else an independent clone() of the acting tool's; another tool's
//    detector is never changed in place by an op that is not its own).
// The bound counts what the entries keep alive: their images' own bytes, and every detector object a
// rows image refers to (SessionImage::detector_object) once no tool holds it any more -- the object a
// stale tool's detector was cloned from before it followed another tool's moved rows
// (EditSession::sync_tool) lives on only for the images that refer to it.
// Undo and redo are last-in first-out per author (issue 11 §3): an author undoes its own last applied
// entry and redoes its own last undone one. While no other author's entry changed state after it, the
// whole image is swapped (exactly as a single author's history); otherwise only the entry's own part is
// (its rows and its author's tool), and only when no other author's later entry touched those surfels
// or renumbered rows (EditSession::swap_own).
#pragma once

#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <unordered_map>
#include <optional>
#include <string>
#include <vector>

#include "surfeledit/core/collision.hpp"
#include "surfeledit/core/deformation.hpp"
#include "surfeledit/core/row_versions.hpp"
#include "surfeledit/core/settings.hpp"
#include "surfeledit/core/surfel_model.hpp"
#include "surfeledit/core/row_versions.hpp"
#include "surfeledit/core/tool.hpp"

namespace surfeledit {

// The rows one step moved, and what the step changes in them.
struct RowsImage {
  std::shared_ptr<const IndexList> rows;   // rows moved by the step, ascending (shared by the images of
                                           // steps over the same deformable rows)
  // The rows among `rows` whose normals and tangents are kept, ascending; null: all of `rows`. A step
  // without rotation leaves the normals and tangents of F1 rows (gradient 0) bit for bit as they were, so
  // its image keeps those of the other rows only (session_history.cpp, step_bent_rows).
  std::shared_ptr<const IndexList> bent;
  Points positions;                        // #rows by 3
  Points normals;                          // #bent rows by 3 (#rows when `bent` is null)
  Points tangent_u, tangent_v;             // like normals, or empty when the model has no tangents
  // Per-row versions as runs (version, count), in the order of `rows`: after a step every moved row has
  // the step's version, so there are few runs.
  std::vector<std::pair<std::uint64_t, std::uint32_t>> version_runs;
};

// Everything a session holds, copied.
struct WholeImage {
  SurfelModel model;
  std::uint64_t model_version = 0;
  RowVersions row_version;                             // #P
  Values rest_radius;                                  // resampling's rest radii (empty when unused)
  HistoryParams history;                               // the session's history bound
  std::map<std::string, ToolImage> tools;              // every tool, by author (detectors: the objects
                                                       // themselves, the acting tool's cloned when asked)
};

// The acting tool alone: an op that changed nothing but that tool (and the history bound).
struct ToolOnlyImage {
  ToolImage tool;          // the tool's state (fields omitted when the op keeps them: ToolImage::fields_kept)
  HistoryParams history;   // the session's history bound
};

// One side (before or after) of an entry.
struct SessionImage {
  std::optional<RowsImage> rows;    // exactly one of rows / tool_only / whole
  std::optional<ToolOnlyImage> tool_only;
  std::optional<WholeImage> whole;
  // Rows images: the state of the tool `tool` that they belong to (a step changes only its own tool).
  std::string tool;                 // author of the step (whole images: the acting tool)
  std::shared_ptr<const DetectorImage> detector;  // the detector's per-row states (null: no detector)
  std::shared_ptr<CollisionDetector> detector_object;  // the object those states belong to (a tool whose
                                    // detector was re-initialised since holds another one)
  bool stale = false;               // the tool's `stale` flag
  IdList colliding;                 // colliding ids
  std::uint64_t steps = 0;          // step counter
  bool complete = true;             // false when the detector could not be saved (a detector without
                                    // save_image): the image cannot be restored

  std::size_t bytes() const;
  // "rows", "tool" or "whole" (the history's split by image kind, EditSession::history_bytes()).
  const char* kind() const;
};

// What history() lists of an entry.
struct HistoryItem {
  std::uint64_t version = 0;  // the session's version after the op
  std::string op;             // "load", "set_regions", "deform", "configure", "remove", "merge", "release", ...
  std::string author;         // client id ("" in-process)
  IdList touched;             // ids of the surfels it changed, inserted or removed, ascending
  bool undone = false;        // in the redo tail
};

struct HistoryEntry {
  HistoryItem item;  // its `touched` is moved to `touched` below when the entry is stored (items() lists it)
  // The ids the op touched (HistoryItem::touched), immutable once stored and shared with snapshot views.
  std::shared_ptr<const IdList> touched;
  // Before the op while applied, after it once undone. Immutable once stored: undo and redo replace it
  // (History::replace_image), and a snapshot view (EditSession::snapshot_view) may share it and read it
  // on another thread; History alone touches a stored image again, and only once no view shares it, or
  // to drop the references a dropped image holds (History::retire).
  std::shared_ptr<const SessionImage> image;
  std::size_t bytes = 0;  // image.bytes(), kept by History
  std::uint64_t stamp = 0;       // the session version of its last apply, undo or redo
  std::uint64_t applied_at = 0;  // the session version of its last apply or redo
};

// The entries of one session, oldest first (in the order they were first applied), each flagged undone
// or not, and the memory bound.
class History {
 public:
  // Appends an applied entry (stamp: its version): drops its author's undone entries (the author's redo
  // tail), then the oldest entries beyond `limit_bytes`.
  void push(HistoryEntry entry, std::size_t limit_bytes);
  // Drops oldest entries until at most `limit_bytes` are held.
  void trim(std::size_t limit_bytes);
  // The entry undo(author) acts on (the author's last applied one) / redo(author) acts on (the author's
  // first undone one); nullptr when there is none.
  HistoryEntry* undo_target(const std::string& author);
  HistoryEntry* redo_target(const std::string& author);
  // Any author's: the last applied entry / the entry undone last (highest stamp).
  HistoryEntry* last_applied();
  HistoryEntry* last_undone();
  // Flags an entry undone or applied again (redone) at version `stamp`.
  void set_undone(HistoryEntry& entry, bool undone, std::uint64_t stamp);
  const std::deque<HistoryEntry>& entries() const { return entries_; }
  void clear();

  std::vector<HistoryItem> items() const;
  // Bytes held: the entries' images plus the detector objects only they keep alive (held_detectors()).
  std::size_t bytes() const { return bytes_ + held_detectors().bytes; }
  // The detector objects that rows images refer to and nothing else holds (no tool, no tool image).
  struct Held {
    std::size_t objects = 0;
    std::size_t bytes = 0;  // their memory_bytes()
  };
  Held held_detectors() const;
  // Replaces an entry's image (undo / redo swap), keeping the byte count.
  void replace_image(HistoryEntry& entry, SessionImage image);
  History() = default;
  History(const History&) = delete;
  History& operator=(const History&) = delete;
  History(History&&) = default;
  History& operator=(History&& other) noexcept;  // retires this one's images first
  ~History();                                     // retires its images (History::retire)
  // Snapshots (session_snapshot.cpp): the entries and spare buffers as saved (each entry's `bytes` kept).
  const std::vector<RowsImage>& spare() const { return spare_; }
  void restore(std::deque<HistoryEntry> entries, std::vector<RowsImage> spare);
  // A rows image of a dropped entry, whose buffers a new image can reuse (empty when there is none):
  // memory already touched costs no page faults.
  RowsImage take_spare();

 private:
  // Keeps the rows image of an entry about to be dropped (at most two are kept), then retires its image.
  void keep_spare(HistoryEntry& entry);
  // Moves an entry's item.touched to its shared `touched` (when not done yet).
  static void share_touched(HistoryEntry& entry);
  // Lets go of an image that leaves the history. One a snapshot view still shares first drops the
  // references it holds (row lists, detector objects and states), which the view does not read: what
  // the history's bound and a stale tool's detector clone count (their owners) is then exactly what it
  // would be without the view; the view frees the arrays when it is done.
  static void retire(std::shared_ptr<const SessionImage>& image);

  // Sums the entries' bytes and counts their detector objects again (after entries were dropped).
  void recount();
  // Counts an image's detector object in (+1) or out (-1) of refs_.
  void count_object(const SessionImage& image, int sign);

  std::deque<HistoryEntry> entries_;
  std::size_t bytes_ = 0;  // the entries' own bytes (HistoryEntry::bytes)
  // Per detector object that images refer to: the object (not owned) and how many images do.
  struct Ref {
    std::weak_ptr<CollisionDetector> object;
    long refs = 0;
  };
  std::unordered_map<const CollisionDetector*, Ref> refs_;
  std::vector<RowsImage> spare_;  // buffers of dropped entries
};

}  // namespace surfeledit
