#include "journal_records.hpp"

#include <dds/dds.h>
#include <dds/ddsi/ddsi_cdrstream.h>

#include <cstring>
#include <limits>

#include "surfeledit/service/journal.hpp"

namespace surfeledit::service::journal {

namespace {

constexpr std::uint32_t kXcdr2 = 2;  // CDR_ENC_VERSION_2

// Little-endian writer of the record payloads.
class Writer {
 public:
  void u8(std::uint8_t v) { out_.push_back(v); }
  void u32(std::uint32_t v) {
    for (int i = 0; i < 4; ++i) out_.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  void u64(std::uint64_t v) {
    for (int i = 0; i < 8; ++i) out_.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  void str(const std::string& s) {
    u32(static_cast<std::uint32_t>(s.size()));
    out_.insert(out_.end(), s.begin(), s.end());
  }
  void bytes(const std::vector<std::uint8_t>& b) { out_.insert(out_.end(), b.begin(), b.end()); }
  std::vector<std::uint8_t> take() { return std::move(out_); }

 private:
  std::vector<std::uint8_t> out_;
};

// Reader of the record payloads; every read is bounds-checked.
class Reader {
 public:
  Reader(const std::vector<std::uint8_t>& in, const char* what) : in_(in), what_(what) {}
  std::uint8_t u8() { return need(1), in_[at_++]; }
  std::uint32_t u32() {
    need(4);
    std::uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= std::uint32_t(in_[at_++]) << (8 * i);
    return v;
  }
  std::uint64_t u64() {
    need(8);
    std::uint64_t v = 0;
    for (int i = 0; i < 8; ++i) v |= std::uint64_t(in_[at_++]) << (8 * i);
    return v;
  }
  std::string str() {
    const std::uint32_t n = u32();
    need(n);
    std::string s(reinterpret_cast<const char*>(in_.data() + at_), n);
    at_ += n;
    return s;
  }
  std::vector<std::uint8_t> rest() {
    std::vector<std::uint8_t> r(in_.begin() + static_cast<std::ptrdiff_t>(at_), in_.end());
    at_ = in_.size();
    return r;
  }
  void end() const {
    if (at_ != in_.size()) throw JournalError(std::string("journal ") + what_ + " record has trailing bytes");
  }

 private:
  void need(std::size_t n) const {
    if (in_.size() - at_ < n) throw JournalError(std::string("journal ") + what_ + " record is cut short");
  }
  const std::vector<std::uint8_t>& in_;
  const char* what_;
  std::size_t at_ = 0;
};

}  // namespace

std::vector<std::uint8_t> encode(const RequestRecord& r) {
  Writer w;
  w.u64(r.version);
  w.u8(r.state_hash ? 1 : 0);
  w.u64(r.state_hash.value_or(0));
  w.str(r.token);
  w.u8(kXcdr2);
  w.bytes(r.cdr);
  return w.take();
}

RequestRecord decode_request(const std::vector<std::uint8_t>& payload) {
  Reader in(payload, "request");
  RequestRecord r;
  r.version = in.u64();
  const bool has_hash = in.u8() != 0;
  const std::uint64_t hash = in.u64();
  if (has_hash) r.state_hash = hash;
  r.token = in.str();
  if (in.u8() != kXcdr2) throw JournalError("journal request record: unknown CDR encoding");
  r.cdr = in.rest();
  return r;
}

std::vector<std::uint8_t> encode(const RefusalRecord& r) {
  Writer w;
  w.str(r.client_id);
  w.u64(r.request_id);
  w.u32(r.request_op);
  w.u32(static_cast<std::uint32_t>(r.status));
  w.str(r.field);
  w.str(r.message);
  w.u64(r.version);
  return w.take();
}

RefusalRecord decode_refusal(const std::vector<std::uint8_t>& payload) {
  Reader in(payload, "refusal");
  RefusalRecord r;
  r.client_id = in.str();
  r.request_id = in.u64();
  r.request_op = in.u32();
  r.status = static_cast<Status>(in.u32());
  r.field = in.str();
  r.message = in.str();
  r.version = in.u64();
  in.end();
  if (r.status == Status::Ok || static_cast<std::uint32_t>(r.status) > static_cast<std::uint32_t>(Status::PermissionDenied)) {
    throw JournalError("journal refusal record with status " + std::to_string(static_cast<std::uint32_t>(r.status)));
  }
  return r;
}

std::vector<std::uint8_t> encode(const ExpiryRecord& r) {
  Writer w;
  w.u32(static_cast<std::uint32_t>(r.expiry.kind));
  w.str(r.expiry.name);
  return w.take();
}

ExpiryRecord decode_expiry(const std::vector<std::uint8_t>& payload) {
  Reader in(payload, "expiry");
  ExpiryRecord r;
  const std::uint32_t kind = in.u32();
  if (kind > static_cast<std::uint32_t>(Expiry::Kind::Forget)) {
    throw JournalError("journal expiry record of kind " + std::to_string(kind));
  }
  r.expiry.kind = static_cast<Expiry::Kind>(kind);
  r.expiry.name = in.str();
  in.end();
  return r;
}

RefusalRecord refusal_of(const Reply& reply) {
  return RefusalRecord{reply.client_id, reply.request_id, reply.request_op, reply.status,
                       reply.field,     reply.message,    reply.version};
}

Reply reply_of(const RefusalRecord& r) {
  Reply reply;
  reply.client_id = r.client_id;
  reply.request_id = r.request_id;
  reply.request_op = r.request_op;
  reply.status = r.status;
  reply.field = r.field;
  reply.message = r.message;
  reply.version = r.version;
  return reply;
}

std::vector<std::uint8_t> sample_cdr(const void* sample, const dds_topic_descriptor_t& type) {
  dds_ostream_t os;
  dds_ostream_init(&os, 0, kXcdr2);
  const bool ok = dds_stream_write(&os, static_cast<const char*>(sample), type.m_ops) != nullptr;
  std::vector<std::uint8_t> out;
  if (ok) out.assign(os.m_buffer, os.m_buffer + os.m_index);
  dds_ostream_fini(&os);
  if (!ok) throw JournalError(std::string("a ") + type.m_typename + " sample could not be serialized for the journal");
  return out;
}

std::vector<std::uint8_t> request_cdr(const surfeledit_proto_Request& request) {
  return sample_cdr(&request, surfeledit_proto_Request_desc);
}

CdrSample::CdrSample(std::vector<std::uint8_t> cdr, const dds_topic_descriptor_t& type) : type_(type) {
  const std::string name = type.m_typename;
  if (cdr.empty()) throw JournalError("journal record holds no " + name + " sample");
  if (cdr.size() > std::numeric_limits<std::uint32_t>::max()) throw JournalError("journal " + name + " too large");
  const auto size = static_cast<std::uint32_t>(cdr.size());
  std::uint32_t offset = 0;
  if (dds_stream_normalize_data(reinterpret_cast<char*>(cdr.data()), &offset, size, false, kXcdr2, type.m_ops) ==
          nullptr ||
      offset != size) {
    throw JournalError("journal record does not hold a valid " + name + " sample");
  }
  sample_ = dds_alloc(type.m_size);
  if (!sample_) throw std::bad_alloc();
  dds_istream_t is;
  dds_istream_init(&is, size, cdr.data(), kXcdr2);
  dds_stream_read(&is, static_cast<char*>(sample_), type.m_ops);
  dds_istream_fini(&is);
}

CdrSample::~CdrSample() {
  if (sample_) dds_sample_free(sample_, &type_, DDS_FREE_ALL);
}

std::vector<std::uint8_t> encode(const SnapshotRecord& r) {
  Writer w;
  w.u64(r.seq);
  w.u64(r.file_bytes);
  w.u32(r.file_crc);
  w.u64(r.records);
  return w.take();
}

SnapshotRecord decode_snapshot(const std::vector<std::uint8_t>& payload) {
  Reader in(payload, "snapshot");
  SnapshotRecord r;
  r.seq = in.u64();
  r.file_bytes = in.u64();
  r.file_crc = in.u32();
  r.records = in.u64();
  in.end();
  return r;
}

}  // namespace surfeledit::service::journal
