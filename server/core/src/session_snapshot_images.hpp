// Snapshot codecs of the session's images (tool, rows and session images of the history and the spare
// buffers) and the pointer tables they refer to by index (session_snapshot.cpp writes the tables and the
// rest of the session around them). Each get_* reads what its put_* wrote and checks it.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "surfeledit/core/detector_snapshot.hpp"
#include "surfeledit/core/edit_session.hpp"
#include "surfeledit/core/snapshot_io.hpp"

namespace surfeledit::snapshot_images {

// Pointer tables: index 0 is null, objects from 1 in first-seen order.
template <typename T>
struct Table {
  std::unordered_map<const T*, std::uint32_t> index;
  std::vector<const T*> list;
  void add(const T* p) {
    if (p && index.emplace(p, static_cast<std::uint32_t>(list.size() + 1)).second) list.push_back(p);
  }
  std::uint32_t at(const T* p) const { return p ? index.at(p) : 0; }
  // Like at(), but 0 for a pointer not in the table (never dereferenced: it may be stale).
  std::uint32_t find(const T* p) const {
    const auto it = index.find(p);
    return it == index.end() ? 0 : it->second;
  }
};

struct Tables {
  Table<CollisionDetector> detectors;
  Table<DetectorImage> images;
  std::vector<const CollisionDetector*> image_owner;  // per image: the detector that reads it
  Table<IndexList> row_lists;
  std::string why;  // not snapshottable: why

  void detector(const CollisionDetector* d, const char* where) {
    if (d && !d->snapshottable() && why.empty())
      why = std::string(where) + ": collision detector '" + to_string(d->params().algorithm) +
            "' with a hierarchy, clusters, Improved's sweep or an inside model has no snapshot";
    detectors.add(d);
  }
  void rows_image(const RowsImage& r) {
    row_lists.add(r.rows.get());
    row_lists.add(r.bent.get());
  }
  void image(const SessionImage& im) {
    detector(im.detector_object.get(), "history");
    if (im.detector) {
      if (!im.detector_object && why.empty()) why = "history: a detector image without its detector";
      const std::size_t before = images.list.size();
      images.add(im.detector.get());
      if (images.list.size() > before) image_owner.push_back(im.detector_object.get());
    }
    if (!im.complete && why.empty()) why = "history: an incomplete image";
    if (im.rows) rows_image(*im.rows);
    if (im.tool_only) detector(im.tool_only->tool.detector.get(), "history");
    if (im.whole)
      for (const auto& [id, t] : im.whole->tools) detector(t.detector.get(), "history");
  }
};

// The objects the tables index, on load.
struct Loaded {
  std::vector<std::shared_ptr<CollisionDetector>> detectors;  // [0] null
  std::vector<std::shared_ptr<const DetectorImage>> images;   // [0] null
  std::vector<std::shared_ptr<const IndexList>> row_lists;    // [0] null

  template <typename T>
  static const T& pick(SnapshotReader& in, const std::vector<T>& v, const char* what) {
    const std::uint32_t k = in.u32(what);
    if (k >= v.size()) in.fail(what, "index " + std::to_string(k) + " out of range");
    return v[k];
  }
};

// The table indices of what an image refers to, taken from the tables at the save's point: an image is
// written from these and its values, never reading its pointers (History::retire may drop those of an
// image a snapshot view shares while the view writes it on another thread).
struct RowsRefs {
  std::uint32_t rows = 0, bent = 0;  // row lists
};
struct ImageRefs {
  RowsRefs rows;                     // a rows image's row lists
  std::uint32_t states = 0;          // the detector image
  std::uint32_t object = 0;          // the detector object
  std::uint32_t tool_detector = 0;   // a tool-only image's tool's detector
  std::vector<std::uint32_t> tools;  // a whole image's tools' detectors, in the order of its tools
};
RowsRefs rows_refs(const Tables& t, const RowsImage& r);
ImageRefs image_refs(const Tables& t, const SessionImage& im);

// `detector`: the table index of the tool image's detector.
void put_tool_image(SnapshotWriter& out, std::uint32_t detector, const ToolImage& im);
ToolImage get_tool_image(SnapshotReader& in, const Loaded& l, std::size_t rows);
// A rows image (an entry's or a spare buffer); get_rows_image reads it.
void put_rows_image(SnapshotWriter& out, const RowsRefs& refs, const RowsImage& r);
void put_image(SnapshotWriter& out, const ImageRefs& refs, const SessionImage& im);
RowsImage get_rows_image(SnapshotReader& in, const Loaded& l);
SessionImage get_image(SnapshotReader& in, const Loaded& l);

}  // namespace surfeledit::snapshot_images
