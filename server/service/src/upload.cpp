#include "surfeledit/service/upload.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <sstream>

namespace surfeledit::service {

namespace {

std::string indexed(const char* field, std::uint64_t row) {
  return std::string(field) + "[" + std::to_string(row) + "]";
}

}  // namespace

Upload::Upload(std::uint64_t total, bool has_radii, const UploadLimits& limits)
    : total_(total), has_radii_(has_radii), limits_(limits) {
  if (total_ == 0) throw Error(ErrorCode::InvalidArgument, "load_begin.total", "an upload needs at least one surfel");
  if (total_ > limits_.max_model_surfels) {
    throw Error(ErrorCode::TooLarge, "load_begin.total",
                std::to_string(total_) + " surfels exceed the limit of " + std::to_string(limits_.max_model_surfels) +
                    " surfels per model");
  }
}

std::uint64_t Upload::bytes() const {
  return sizeof(double) * (positions_.capacity() + normals_.capacity() + radii_.capacity());
}

void Upload::add_chunk(const ChunkData& c, std::uint64_t max_bytes) {
  if (c.positions_len % 3 != 0) {
    throw Error(ErrorCode::InvalidArgument, "load_chunk.positions",
                "length " + std::to_string(c.positions_len) + " is not a multiple of 3 (n*3 expected)");
  }
  const std::uint64_t n = c.positions_len / 3;
  if (n > limits_.max_chunk_surfels) {
    throw Error(ErrorCode::TooLarge, "load_chunk.positions",
                std::to_string(n) + " surfels exceed the limit of " + std::to_string(limits_.max_chunk_surfels) +
                    " surfels per chunk");
  }
  if (c.normals_len != 3 * n) {
    throw Error(ErrorCode::InvalidArgument, "load_chunk.normals",
                "length " + std::to_string(c.normals_len) + ", expected " + std::to_string(3 * n) + " (n*3)");
  }
  const std::uint64_t radii_expected = has_radii_ ? n : 0;
  if (c.radii_len != radii_expected) {
    throw Error(ErrorCode::InvalidArgument, "load_chunk.radii",
                "length " + std::to_string(c.radii_len) + ", expected " + std::to_string(radii_expected) +
                    (has_radii_ ? " (one per surfel)" : " (the upload was begun without radii)"));
  }
  if (c.offset != received_) {
    throw Error(ErrorCode::Conflict, "load_chunk.offset",
                "offset " + std::to_string(c.offset) + " but " + std::to_string(received_) +
                    " surfels were received so far");
  }
  if (n > total_ - received_) {
    throw Error(ErrorCode::InvalidArgument, "load_chunk.positions",
                std::to_string(n) + " surfels at offset " + std::to_string(c.offset) + " exceed the announced total of " +
                    std::to_string(total_));
  }
  for (std::uint64_t i = 0; i < n; ++i) {
    const double* p = c.positions + 3 * i;
    const double* q = c.normals + 3 * i;
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
      throw Error(ErrorCode::InvalidArgument, indexed("load_chunk.positions", i),
                  "non-finite position of surfel " + std::to_string(c.offset + i));
    }
    if (!std::isfinite(q[0]) || !std::isfinite(q[1]) || !std::isfinite(q[2])) {
      throw Error(ErrorCode::InvalidArgument, indexed("load_chunk.normals", i),
                  "non-finite normal of surfel " + std::to_string(c.offset + i));
    }
    if (q[0] == 0.0 && q[1] == 0.0 && q[2] == 0.0) {
      throw Error(ErrorCode::InvalidArgument, indexed("load_chunk.normals", i),
                  "zero normal of surfel " + std::to_string(c.offset + i));
    }
    if (has_radii_ && !(std::isfinite(c.radii[i]) && c.radii[i] > 0.0)) {
      std::ostringstream msg;
      msg << "radius " << c.radii[i] << " of surfel " << (c.offset + i) << " is not finite and positive";
      throw Error(ErrorCode::InvalidArgument, indexed("load_chunk.radii", i), msg.str());
    }
  }
  // Reserve: geometric growth capped at the total, or just what this chunk needs when the
  // geometric step would exceed the budget (then TooLarge when even that does not fit).
  const std::uint64_t per_row = has_radii_ ? 7 : 6;  // doubles
  const std::uint64_t need_rows = received_ + n;
  const std::uint64_t have_rows = positions_.capacity() / 3;
  if (need_rows > have_rows) {
    std::uint64_t rows = std::min<std::uint64_t>(total_, std::max<std::uint64_t>(need_rows, 2 * have_rows));
    if (rows * per_row * sizeof(double) > max_bytes) rows = need_rows;
    if (rows * per_row * sizeof(double) > max_bytes) {
      throw Error(ErrorCode::TooLarge, "load_chunk",
                  "upload memory limit: " + std::to_string(need_rows * per_row * sizeof(double)) +
                      " bytes needed for " + std::to_string(need_rows) + " surfels, " + std::to_string(max_bytes) +
                      " allowed");
    }
    positions_.reserve(3 * rows);
    normals_.reserve(3 * rows);
    if (has_radii_) radii_.reserve(rows);
  }
  positions_.insert(positions_.end(), c.positions, c.positions + 3 * n);
  normals_.insert(normals_.end(), c.normals, c.normals + 3 * n);
  if (has_radii_) radii_.insert(radii_.end(), c.radii, c.radii + n);
  received_ += n;
}

SurfelArrays Upload::arrays() const {
  SurfelArrays out;
  const auto rows = static_cast<Eigen::Index>(received_);
  out.positions.resize(rows, 3);
  out.normals.resize(rows, 3);
  if (has_radii_) out.radii.resize(rows);
  for (Eigen::Index r = 0; r < rows; ++r) {
    for (int k = 0; k < 3; ++k) {
      out.positions(r, k) = positions_[3 * r + k];
      out.normals(r, k) = normals_[3 * r + k];
    }
    if (has_radii_) out.radii(r) = radii_[r];
  }
  return out;
}

SurfelArrays Upload::take() {
  if (!complete()) {
    throw Error(ErrorCode::Conflict, "load_begin.total",
                "upload incomplete: received " + std::to_string(received_) + " of " + std::to_string(total_) +
                    " surfels");
  }
  SurfelArrays out = arrays();
  positions_ = {};
  normals_ = {};
  radii_ = {};
  received_ = 0;
  total_ = 0;
  return out;
}

Upload& UploadTable::begin(const std::string& client, const std::string& session, std::uint64_t total,
                           bool has_radii) {
  Upload fresh(total, has_radii, limits_);  // validates before replacing anything
  Key key(client, session);
  if (auto it = uploads_.find(key); it != uploads_.end()) erase(it);
  return uploads_.emplace(std::move(key), std::move(fresh)).first->second;
}

Upload* UploadTable::find(const std::string& client, const std::string& session) {
  auto it = uploads_.find(Key(client, session));
  return it == uploads_.end() ? nullptr : &it->second;
}

void UploadTable::add_chunk(const std::string& client, const std::string& session, const ChunkData& chunk) {
  auto it = uploads_.find(Key(client, session));
  if (it == uploads_.end()) {
    throw Error(ErrorCode::Conflict, "load_chunk", "no upload in progress: send OP_LOAD_BEGIN first");
  }
  Upload& upload = it->second;
  const std::uint64_t before = upload.bytes();
  const std::uint64_t mine = client_bytes(client);
  // What this upload may grow to: its own memory plus what is left of both budgets.
  const std::uint64_t client_room = limits_.max_client_bytes > mine ? limits_.max_client_bytes - mine : 0;
  const std::uint64_t total_room = limits_.max_total_bytes > total_bytes_ ? limits_.max_total_bytes - total_bytes_ : 0;
  try {
    upload.add_chunk(chunk, before + std::min(client_room, total_room));
  } catch (const Error& e) {
    if (e.code() != ErrorCode::TooLarge || e.field() != "load_chunk") throw;
    const bool client_limit = client_room <= total_room;
    throw Error(ErrorCode::TooLarge, "load_chunk",
                std::string(e.what()) + " (" + (client_limit ? "per-client limit " : "server-wide limit ") +
                    std::to_string(client_limit ? limits_.max_client_bytes : limits_.max_total_bytes) +
                    " bytes of unfinished uploads; this client holds " + std::to_string(mine) + ", all clients " +
                    std::to_string(total_bytes_) + ")");
  }
  const std::uint64_t grown = upload.bytes() - before;
  client_bytes_[client] += grown;
  total_bytes_ += grown;
}

void UploadTable::erase(std::map<Key, Upload>::iterator it) {
  const std::uint64_t b = it->second.bytes();
  auto cb = client_bytes_.find(it->first.first);
  if (cb != client_bytes_.end()) {
    cb->second -= std::min(cb->second, b);
    if (cb->second == 0) client_bytes_.erase(cb);
  }
  total_bytes_ -= std::min(total_bytes_, b);
  uploads_.erase(it);
}

void UploadTable::erase(const std::string& client, const std::string& session) {
  auto it = uploads_.find(Key(client, session));
  if (it != uploads_.end()) erase(it);
}

void UploadTable::erase_session(const std::string& session) {
  for (auto it = uploads_.begin(); it != uploads_.end();) {
    auto next = std::next(it);
    if (it->first.second == session) erase(it);
    it = next;
  }
}

void UploadTable::erase_client(const std::string& client) {
  for (auto it = uploads_.lower_bound(Key(client, std::string())); it != uploads_.end() && it->first.first == client;) {
    auto next = std::next(it);
    erase(it);
    it = next;
  }
}

std::uint64_t UploadTable::client_bytes(const std::string& client) const {
  auto it = client_bytes_.find(client);
  return it == client_bytes_.end() ? 0 : it->second;
}

}  // namespace surfeledit::service
