#include "surfeledit/service/upload.hpp"

#include <cmath>
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
  const auto rows = static_cast<Eigen::Index>(total_);
  arrays_.positions.resize(rows, 3);
  arrays_.normals.resize(rows, 3);
  if (has_radii_) arrays_.radii.resize(rows);
}

void Upload::add_chunk(const ChunkData& c) {
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
  for (std::uint64_t i = 0; i < n; ++i) {
    const auto row = static_cast<Eigen::Index>(received_ + i);
    for (int k = 0; k < 3; ++k) {
      arrays_.positions(row, k) = c.positions[3 * i + k];
      arrays_.normals(row, k) = c.normals[3 * i + k];
    }
    if (has_radii_) arrays_.radii(row) = c.radii[i];
  }
  received_ += n;
}

SurfelArrays Upload::take() {
  if (!complete()) {
    throw Error(ErrorCode::Conflict, "load_begin.total",
                "upload incomplete: received " + std::to_string(received_) + " of " + std::to_string(total_) +
                    " surfels");
  }
  SurfelArrays out = std::move(arrays_);
  arrays_ = SurfelArrays();
  received_ = 0;
  total_ = 0;
  return out;
}

Upload& UploadTable::begin(const std::string& client, const std::string& session, std::uint64_t total,
                           bool has_radii) {
  Upload fresh(total, has_radii, limits_);  // validates (and allocates) before replacing anything
  auto key = std::make_pair(client, session);
  uploads_.erase(key);
  return uploads_.emplace(std::move(key), std::move(fresh)).first->second;
}

Upload* UploadTable::find(const std::string& client, const std::string& session) {
  auto it = uploads_.find(std::make_pair(client, session));
  return it == uploads_.end() ? nullptr : &it->second;
}

void UploadTable::erase(const std::string& client, const std::string& session) {
  uploads_.erase(std::make_pair(client, session));
}

void UploadTable::erase_session(const std::string& session) {
  for (auto it = uploads_.begin(); it != uploads_.end();) {
    if (it->first.second == session) it = uploads_.erase(it);
    else ++it;
  }
}

}  // namespace surfeledit::service
