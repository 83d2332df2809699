// Service pieces that need no network: request cache, uploads, conversions, update chunks,
// and the request handler (idempotence, atomicity, paging) driven with generated C requests.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <variant>
#include <vector>

#include "surfeledit/service/convert.hpp"
#include "surfeledit/service/handler.hpp"
#include "surfeledit/service/request_cache.hpp"
#include "surfeledit/service/update.hpp"
#include "surfeledit/service/update_publisher.hpp"
#include "surfeledit/service/upload.hpp"

using namespace surfeledit;
using namespace surfeledit::service;

namespace {

std::shared_ptr<const Reply> reply_for(const std::string& client, std::uint64_t id, const std::string& message = "") {
  auto r = std::make_shared<Reply>();
  r->client_id = client;
  r->request_id = id;
  r->message = message;
  return r;
}

// Expects `f` to throw surfeledit::Error with `code` and a field starting with `field`.
template <typename F>
void expect_error(F&& f, ErrorCode code, const std::string& field) {
  try {
    f();
    ADD_FAILURE() << "no error thrown; expected field " << field;
  } catch (const Error& e) {
    EXPECT_EQ(static_cast<int>(e.code()), static_cast<int>(code)) << e.what();
    EXPECT_EQ(e.field().rfind(field, 0), 0u) << "field '" << e.field() << "' does not start with '" << field << "'";
  }
}

// A chunk of n surfels on the unit sphere (positions = normals), radii 0.1.
struct ChunkArrays {
  std::vector<double> positions, normals, radii;
  ChunkData data(std::uint64_t offset, bool with_radii = true) const {
    ChunkData c;
    c.offset = offset;
    c.positions = positions.data();
    c.positions_len = positions.size();
    c.normals = normals.data();
    c.normals_len = normals.size();
    c.radii = with_radii ? radii.data() : nullptr;
    c.radii_len = with_radii ? radii.size() : 0;
    return c;
  }
};

ChunkArrays sphere_chunk(std::size_t n, std::size_t first = 0, std::size_t total = 0) {
  if (total == 0) total = n;
  ChunkArrays a;
  for (std::size_t i = first; i < first + n; ++i) {
    // Fibonacci sphere point i of total.
    const double z = 1.0 - 2.0 * (static_cast<double>(i) + 0.5) / static_cast<double>(total);
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = 2.399963229728653 * static_cast<double>(i);
    const double p[3] = {r * std::cos(phi), r * std::sin(phi), z};
    for (double v : p) {
      a.positions.push_back(v);
      a.normals.push_back(v);
    }
    a.radii.push_back(0.1);
  }
  return a;
}

// A generated C request whose strings and sequences point into this object.
struct RequestBuilder {
  std::string client = "client-a";
  std::string session = "s";
  surfeledit_proto_Request req{};
  surfeledit_proto_LoadBegin load_begin{};
  surfeledit_proto_LoadChunk load_chunk{};
  surfeledit_proto_SetRegions set_regions{};
  surfeledit_proto_Deform deform{};
  surfeledit_proto_GetState get_state{};
  std::string blend = "linear";

  const surfeledit_proto_Request& make(surfeledit_proto_Op op, std::uint64_t id) {
    req = surfeledit_proto_Request{};
    req.client_id = const_cast<char*>(client.c_str());
    req.session = const_cast<char*>(session.c_str());
    req.request_id = id;
    req.op = op;
    auto one = [](auto& seq, auto* element) {
      seq._length = seq._maximum = 1;
      seq._buffer = element;
    };
    switch (op) {
      case surfeledit_proto_OP_LOAD_BEGIN: one(req.load_begin, &load_begin); break;
      case surfeledit_proto_OP_LOAD_CHUNK: one(req.load_chunk, &load_chunk); break;
      case surfeledit_proto_OP_SET_REGIONS: one(req.set_regions, &set_regions); break;
      case surfeledit_proto_OP_DEFORM:
        deform.blend = const_cast<char*>(blend.c_str());
        one(req.deform, &deform);
        break;
      case surfeledit_proto_OP_GET_STATE: one(req.get_state, &get_state); break;
      default: break;
    }
    return req;
  }
};

template <typename Seq, typename T>
void point_to(Seq& seq, std::vector<T>& v) {
  seq._length = seq._maximum = static_cast<uint32_t>(v.size());
  seq._buffer = v.data();
}

}  // namespace

// --- request cache ---------------------------------------------------------------------------

TEST(RequestCache, StoresAndFindsPerClient) {
  RequestCache cache;
  cache.put(reply_for("a", 1, "a1"));
  cache.put(reply_for("b", 1, "b1"));
  ASSERT_NE(cache.find("a", 1), nullptr);
  EXPECT_EQ(cache.find("a", 1)->message, "a1");
  EXPECT_EQ(cache.find("b", 1)->message, "b1");
  EXPECT_EQ(cache.find("a", 2), nullptr);
  EXPECT_EQ(cache.find("c", 1), nullptr);
  EXPECT_EQ(cache.clients(), 2u);
}

TEST(RequestCache, KeepsTheLast1024RepliesPerClient) {
  RequestCache cache;
  for (std::uint64_t id = 1; id <= 1500; ++id) cache.put(reply_for("a", id));
  EXPECT_EQ(cache.size("a"), 1024u);
  EXPECT_EQ(cache.find("a", 476), nullptr);  // 1500 - 1024 = 476 evicted
  EXPECT_NE(cache.find("a", 477), nullptr);
  EXPECT_NE(cache.find("a", 1500), nullptr);
}

TEST(RequestCache, AHitRefreshesRecency) {
  RequestCache cache(3);
  cache.put(reply_for("a", 1));
  cache.put(reply_for("a", 2));
  cache.put(reply_for("a", 3));
  ASSERT_NE(cache.find("a", 1), nullptr);  // 1 is now the most recent
  cache.put(reply_for("a", 4));            // evicts 2
  EXPECT_NE(cache.find("a", 1), nullptr);
  EXPECT_EQ(cache.find("a", 2), nullptr);
  EXPECT_NE(cache.find("a", 3), nullptr);
  EXPECT_NE(cache.find("a", 4), nullptr);
}

TEST(RequestCache, ForgetsTheLeastRecentlyActiveClient) {
  RequestCache cache(4, 2);
  cache.put(reply_for("a", 1));
  cache.put(reply_for("b", 1));
  ASSERT_NE(cache.find("a", 1), nullptr);  // a active again
  cache.put(reply_for("c", 1));            // b is forgotten
  EXPECT_NE(cache.find("a", 1), nullptr);
  EXPECT_EQ(cache.find("b", 1), nullptr);
  EXPECT_NE(cache.find("c", 1), nullptr);
  cache.forget("a");
  EXPECT_EQ(cache.find("a", 1), nullptr);
  EXPECT_EQ(cache.clients(), 1u);
}

TEST(RequestCache, PutReplacesTheSameId) {
  RequestCache cache;
  cache.put(reply_for("a", 7, "old"));
  cache.put(reply_for("a", 7, "new"));
  EXPECT_EQ(cache.size("a"), 1u);
  EXPECT_EQ(cache.find("a", 7)->message, "new");
}

// --- uploads ---------------------------------------------------------------------------------

TEST(Upload, AcceptsChunksInOrderAndHandsOverTheArrays) {
  Upload up(5, true, UploadLimits{3, 100});
  const ChunkArrays first = sphere_chunk(3, 0, 5), second = sphere_chunk(2, 3, 5);
  up.add_chunk(first.data(0));
  EXPECT_EQ(up.received(), 3u);
  EXPECT_FALSE(up.complete());
  up.add_chunk(second.data(3));
  ASSERT_TRUE(up.complete());
  const SurfelArrays a = up.take();
  ASSERT_EQ(a.positions.rows(), 5);
  EXPECT_DOUBLE_EQ(a.positions(4, 2), second.positions[5]);
  EXPECT_DOUBLE_EQ(a.normals(0, 0), first.normals[0]);
  EXPECT_DOUBLE_EQ(a.radii(3), 0.1);
}

TEST(Upload, RejectsAnOffsetMismatchAndKeepsWhatItHas) {
  Upload up(4, true, UploadLimits{4, 100});
  const ChunkArrays c = sphere_chunk(2, 0, 4);
  up.add_chunk(c.data(0));
  expect_error([&] { up.add_chunk(c.data(0)); }, ErrorCode::Conflict, "load_chunk.offset");
  expect_error([&] { up.add_chunk(c.data(3)); }, ErrorCode::Conflict, "load_chunk.offset");
  EXPECT_EQ(up.received(), 2u);
}

TEST(Upload, RejectsWrongSizes) {
  Upload up(10, true, UploadLimits{8, 100});
  ChunkArrays c = sphere_chunk(2, 0, 10);
  ChunkData d = c.data(0);
  d.positions_len = 5;
  expect_error([&] { up.add_chunk(d); }, ErrorCode::InvalidArgument, "load_chunk.positions");
  d = c.data(0);
  d.normals_len = 3;
  expect_error([&] { up.add_chunk(d); }, ErrorCode::InvalidArgument, "load_chunk.normals");
  d = c.data(0);
  d.radii_len = 1;
  expect_error([&] { up.add_chunk(d); }, ErrorCode::InvalidArgument, "load_chunk.radii");
  expect_error([&] { up.add_chunk(c.data(0, false)); }, ErrorCode::InvalidArgument, "load_chunk.radii");
  EXPECT_EQ(up.received(), 0u);

  Upload no_radii(2, false, UploadLimits{8, 100});
  expect_error([&] { no_radii.add_chunk(c.data(0, true)); }, ErrorCode::InvalidArgument, "load_chunk.radii");
  no_radii.add_chunk(c.data(0, false));
  EXPECT_TRUE(no_radii.complete());
  EXPECT_EQ(no_radii.take().radii.size(), 0);
}

TEST(Upload, RejectsWhatIsTooLarge) {
  expect_error([] { Upload(101, true, UploadLimits{8, 100}); }, ErrorCode::TooLarge, "load_begin.total");
  expect_error([] { Upload(0, true, UploadLimits{8, 100}); }, ErrorCode::InvalidArgument, "load_begin.total");
  Upload up(20, true, UploadLimits{4, 100});
  const ChunkArrays big = sphere_chunk(5, 0, 20);
  expect_error([&] { up.add_chunk(big.data(0)); }, ErrorCode::TooLarge, "load_chunk.positions");
  Upload small(3, true, UploadLimits{8, 100});
  expect_error([&] { small.add_chunk(big.data(0)); }, ErrorCode::InvalidArgument, "load_chunk.positions");
}

TEST(Upload, RejectsBadValuesNamingTheRow) {
  Upload up(3, true, UploadLimits{8, 100});
  ChunkArrays c = sphere_chunk(3);
  c.positions[4] = std::numeric_limits<double>::quiet_NaN();
  expect_error([&] { up.add_chunk(c.data(0)); }, ErrorCode::InvalidArgument, "load_chunk.positions[1]");
  c = sphere_chunk(3);
  c.normals[6] = c.normals[7] = c.normals[8] = 0.0;
  expect_error([&] { up.add_chunk(c.data(0)); }, ErrorCode::InvalidArgument, "load_chunk.normals[2]");
  c = sphere_chunk(3);
  c.radii[0] = -1.0;
  expect_error([&] { up.add_chunk(c.data(0)); }, ErrorCode::InvalidArgument, "load_chunk.radii[0]");
  EXPECT_EQ(up.received(), 0u);
}

TEST(Upload, TakeRequiresACompleteUpload) {
  Upload up(3, true, UploadLimits{8, 100});
  expect_error([&] { up.take(); }, ErrorCode::Conflict, "load_begin.total");
}

TEST(UploadTable, OneUploadPerClientAndSession) {
  UploadTable t(UploadLimits{8, 100});
  t.begin("a", "s", 3, true);
  t.begin("b", "s", 4, true);
  t.begin("a", "t", 5, false);
  EXPECT_EQ(t.size(), 3u);
  EXPECT_EQ(t.find("a", "s")->total(), 3u);
  t.begin("a", "s", 6, true);  // restarts
  EXPECT_EQ(t.find("a", "s")->total(), 6u);
  expect_error([&] { t.begin("a", "s", 1000, true); }, ErrorCode::TooLarge, "load_begin.total");
  EXPECT_EQ(t.find("a", "s")->total(), 6u);  // a failed begin keeps the old upload
  t.erase_session("s");
  EXPECT_EQ(t.size(), 1u);
  EXPECT_EQ(t.find("a", "s"), nullptr);
}

// --- conversions -----------------------------------------------------------------------------

TEST(Convert, StatusNumbersEqualErrorCodes) {
  EXPECT_EQ(static_cast<int>(status_of(ErrorCode::InvalidArgument)), surfeledit_proto_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(static_cast<int>(status_of(ErrorCode::NotFound)), surfeledit_proto_STATUS_NOT_FOUND);
  EXPECT_EQ(static_cast<int>(status_of(ErrorCode::Conflict)), surfeledit_proto_STATUS_CONFLICT);
  EXPECT_EQ(static_cast<int>(status_of(ErrorCode::TooLarge)), surfeledit_proto_STATUS_TOO_LARGE);
  EXPECT_EQ(static_cast<int>(status_of(ErrorCode::Io)), surfeledit_proto_STATUS_IO);
  EXPECT_EQ(static_cast<int>(status_of(ErrorCode::Internal)), surfeledit_proto_STATUS_INTERNAL);
}

TEST(Convert, Selectors) {
  surfeledit_proto_Selector s{};
  s.kind = surfeledit_proto_SELECTOR_BOX;
  s.center = {1, 2, 3};
  s.half_extents = {0.5, 0.5, 0.5};
  const Selector box = to_core(s, "set_regions.one.selectors[0]");
  EXPECT_EQ(box.kind, Selector::Kind::Box);
  EXPECT_EQ(box.center, Vec3(1, 2, 3));
  EXPECT_EQ(box.half_extents, Vec3(0.5, 0.5, 0.5));

  s.kind = static_cast<surfeledit_proto_SelectorKind>(7);
  expect_error([&] { to_core(s, "sel"); }, ErrorCode::InvalidArgument, "sel.kind");
  s.kind = surfeledit_proto_SELECTOR_SPHERE;
  s.radius = -1.0;
  expect_error([&] { to_core(s, "sel"); }, ErrorCode::InvalidArgument, "sel");
}

TEST(Convert, RegionSpecs) {
  std::vector<uint64_t> ids = {3, 1, 2};
  std::vector<surfeledit_proto_Selector> sels(2);
  sels[0].kind = surfeledit_proto_SELECTOR_SPHERE;
  sels[0].radius = 1.0;
  sels[1].kind = surfeledit_proto_SELECTOR_SPHERE;
  sels[1].radius = std::numeric_limits<double>::infinity() * 0.0;  // NaN
  surfeledit_proto_RegionSpec r{};
  point_to(r.ids, ids);
  r.selectors._length = 1;
  r.selectors._buffer = sels.data();
  const RegionSpec spec = to_core(r, "set_regions.zero");
  EXPECT_EQ(spec.ids, (IdList{3, 1, 2}));
  ASSERT_EQ(spec.selectors.size(), 1u);
  EXPECT_DOUBLE_EQ(spec.selectors[0].radius, 1.0);
  r.selectors._length = 2;
  expect_error([&] { to_core(r, "set_regions.zero"); }, ErrorCode::InvalidArgument, "set_regions.zero.selectors[1]");
}

TEST(Convert, DeformParams) {
  surfeledit_proto_Deform d{};
  d.translation = {0, 0, 1};
  d.axis = {0, 1, 0};
  d.angle = 0.5;
  std::string blend;
  d.blend = const_cast<char*>(blend.c_str());
  DeformParams p = to_core(d, "deform");
  EXPECT_EQ(p.blend, Blend::Smooth);  // empty -> smooth
  EXPECT_FALSE(p.center.has_value());
  EXPECT_EQ(p.translation, Vec3(0, 0, 1));
  blend = "linear";
  d.blend = const_cast<char*>(blend.c_str());
  d.has_center = true;
  d.center = {1, 1, 1};
  p = to_core(d, "deform");
  EXPECT_EQ(p.blend, Blend::Linear);
  ASSERT_TRUE(p.center.has_value());
  EXPECT_EQ(*p.center, Vec3(1, 1, 1));
  blend = "wobbly";
  d.blend = const_cast<char*>(blend.c_str());
  expect_error([&] { to_core(d, "deform"); }, ErrorCode::InvalidArgument, "deform.blend");
  blend = "smooth";
  d.blend = const_cast<char*>(blend.c_str());
  d.axis = {0, 0, 0};
  expect_error([&] { to_core(d, "deform"); }, ErrorCode::InvalidArgument, "deform.");
  d.axis = {0, 0, 1};
  d.translation.x = std::numeric_limits<double>::quiet_NaN();
  expect_error([&] { to_core(d, "deform"); }, ErrorCode::InvalidArgument, "deform.");
}

TEST(Convert, PrefixedErrorsKeepCodeAndMessage) {
  try {
    rethrow_prefixed(Error(ErrorCode::NotFound, "ids", "id 7 is unknown"), "set_regions");
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::NotFound);
    EXPECT_EQ(e.field(), "set_regions.ids");
    EXPECT_EQ(message_of(e), "id 7 is unknown");
  }
  try {
    rethrow_prefixed(Error(ErrorCode::Conflict, "deform.axis", "x"), "deform");
  } catch (const Error& e) {
    EXPECT_EQ(e.field(), "deform.axis");
  }
}

TEST(Convert, ReplyViewPresentsEveryField) {
  Reply r;
  r.client_id = "c";
  r.request_id = 42;
  r.status = Status::Conflict;
  r.field = "session";
  r.message = "m";
  r.version = 9;
  r.timings = {{"total", 1.5}, {"apply", 0.5}};
  StatePage page;
  page.full = true;
  page.total = 10;
  page.offset = 4;
  page.ids = {4, 5};
  page.positions = {1, 2, 3, 4, 5, 6};
  page.normals = {0, 0, 1, 0, 0, 1};
  page.radii = {0.1, 0.2};
  r.state = page;
  SessionInfo si;
  si.name = "s";
  si.surfels = 2;
  si.structures = {{"model", 100}};
  r.session_info = si;
  ServerInfo sv;
  sv.version = "0.1.0";
  sv.sessions = {"a", "b"};
  sv.max_chunk_surfels = 65536;
  r.server_info = sv;
  StepInfo st;
  st.seq = 3;
  st.moved = 2;
  st.center = {1, 2, 3};
  r.step = st;

  const ReplyView view(r);
  const surfeledit_proto_Reply& m = *view.get();
  EXPECT_STREQ(m.client_id, "c");
  EXPECT_EQ(m.request_id, 42u);
  EXPECT_EQ(m.status, surfeledit_proto_STATUS_CONFLICT);
  EXPECT_STREQ(m.field, "session");
  EXPECT_EQ(m.version, 9u);
  ASSERT_EQ(m.timings._length, 2u);
  EXPECT_STREQ(m.timings._buffer[1].name, "apply");
  ASSERT_EQ(m.state._length, 1u);
  EXPECT_EQ(m.state._buffer[0].offset, 4u);
  ASSERT_EQ(m.state._buffer[0].positions._length, 6u);
  EXPECT_DOUBLE_EQ(m.state._buffer[0].positions._buffer[5], 6.0);
  EXPECT_EQ(m.state._buffer[0].removed._length, 0u);
  ASSERT_EQ(m.session_info._length, 1u);
  EXPECT_STREQ(m.session_info._buffer[0].structures._buffer[0].name, "model");
  ASSERT_EQ(m.server_info._length, 1u);
  ASSERT_EQ(m.server_info._buffer[0].sessions._length, 2u);
  EXPECT_STREQ(m.server_info._buffer[0].sessions._buffer[1], "b");
  ASSERT_EQ(m.step._length, 1u);
  EXPECT_DOUBLE_EQ(m.step._buffer[0].center.z, 3.0);
  EXPECT_FALSE(m.timings._release);

  const Reply empty;
  const ReplyView none(empty);
  EXPECT_EQ(none.get()->state._length, 0u);
  EXPECT_EQ(none.get()->session_info._length, 0u);
  EXPECT_EQ(none.get()->server_info._length, 0u);
  EXPECT_EQ(none.get()->step._length, 0u);
}

// --- update chunks ---------------------------------------------------------------------------

TEST(Update, PreparedUpdatesCopyTheRowsAndChunkIntoSlices) {
  const ChunkArrays c = sphere_chunk(5);
  SurfelArrays a;
  a.positions = Eigen::Map<const Points>(c.positions.data(), 5, 3);
  a.normals = Eigen::Map<const Points>(c.normals.data(), 5, 3);
  a.radii = Eigen::Map<const Values>(c.radii.data(), 5);
  const SurfelModel model = SurfelModel::from_arrays(a);

  UpdateEvent all;
  all.session = "s";
  all.version = 1;
  all.cause = "load";
  all.full = true;
  all.all_rows = true;
  all.removed = {99};
  const PreparedUpdate full = prepare_update(all, &model);
  ASSERT_EQ(full.surfels(), 5u);
  EXPECT_EQ(full.ids, model.ids());
  EXPECT_DOUBLE_EQ(full.positions[3 * 4 + 2], model.positions()(4, 2));
  EXPECT_DOUBLE_EQ(full.normals[3 * 2 + 1], model.normals()(2, 1));
  EXPECT_DOUBLE_EQ(full.radii[3], model.radii()(3));
  ASSERT_EQ(update_parts(full, 2), 3u);
  const UpdateChunk last = update_chunk(full, 2, 2);
  EXPECT_EQ(last.part, 2u);
  EXPECT_EQ(last.parts, 3u);
  EXPECT_EQ(last.begin, 4u);
  EXPECT_EQ(last.count, 1u);
  EXPECT_THROW(update_chunk(full, 3, 2), std::out_of_range);

  // The sample view: slices of the prepared arrays; removed / collision state in part 0 only.
  PreparedUpdate with_collision = full;
  with_collision.detected = true;
  with_collision.colliding = {1, 3};
  const UpdateView v2(update_chunk(with_collision, 2, 2));
  ASSERT_EQ(v2.get()->ids._length, 1u);
  EXPECT_EQ(v2.get()->ids._buffer[0], model.ids()[4]);
  ASSERT_EQ(v2.get()->positions._length, 3u);
  EXPECT_DOUBLE_EQ(v2.get()->positions._buffer[2], model.positions()(4, 2));
  EXPECT_EQ(v2.get()->removed._length, 0u);
  EXPECT_FALSE(v2.get()->detected);
  EXPECT_EQ(v2.get()->colliding._length, 0u);
  const UpdateView v0(update_chunk(with_collision, 0, 2));
  EXPECT_EQ(v0.get()->part, 0u);
  EXPECT_EQ(v0.get()->parts, 3u);
  ASSERT_EQ(v0.get()->removed._length, 1u);
  EXPECT_EQ(v0.get()->removed._buffer[0], 99u);
  EXPECT_TRUE(v0.get()->detected);
  ASSERT_EQ(v0.get()->colliding._length, 2u);
  EXPECT_EQ(v0.get()->colliding._buffer[1], 3u);
  EXPECT_STREQ(v0.get()->cause, "load");
  EXPECT_FALSE(v0.get()->ids._release);

  UpdateEvent some;
  some.cause = "deform";
  some.rows = {1, 3};
  const PreparedUpdate two = prepare_update(some, &model);
  ASSERT_EQ(update_parts(two, 65536), 1u);
  EXPECT_EQ(two.ids, (std::vector<std::uint64_t>{model.ids()[1], model.ids()[3]}));
  EXPECT_EQ(two.radii.size(), 2u);
  some.rows = {7};
  EXPECT_THROW(prepare_update(some, &model), std::out_of_range);

  UpdateEvent close;
  close.cause = "close";
  const PreparedUpdate none = prepare_update(close, nullptr);
  EXPECT_EQ(update_parts(none, 2), 1u);
  EXPECT_EQ(update_chunk(none, 0, 2).count, 0u);
  const UpdateView vc(update_chunk(none, 0, 2));
  EXPECT_EQ(vc.get()->ids._length, 0u);
}

// --- update publisher ------------------------------------------------------------------------

namespace {

PreparedUpdate small_update(const std::string& session, std::uint64_t version, const std::string& cause,
                            std::size_t surfels = 10) {
  PreparedUpdate u;
  u.session = session;
  u.version = version;
  u.cause = cause;
  u.ids.assign(surfels, version);
  u.positions.assign(3 * surfels, 0.0);
  u.normals.assign(3 * surfels, 0.0);
  u.radii.assign(surfels, 0.0);
  return u;
}

// A writer that records what it wrote and can be held (to let the queue fill up).
struct RecordingWriter {
  std::mutex mutex;
  std::condition_variable cv;
  bool hold = false;
  std::vector<std::pair<std::string, std::uint64_t>> written;
  std::thread::id thread;

  UpdatePublisher::Writer writer() {
    return [this](const PreparedUpdate& u) {
      std::unique_lock<std::mutex> lock(mutex);
      cv.wait(lock, [&] { return !hold; });
      thread = std::this_thread::get_id();
      if (u.cause == "boom") throw std::runtime_error("write failed");
      written.emplace_back(u.session, u.version);
    };
  }
  void set_hold(bool h) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      hold = h;
    }
    cv.notify_all();
  }
};

}  // namespace

TEST(UpdatePublisher, WritesInOrderOnItsOwnThread) {
  RecordingWriter w;
  UpdatePublisher pub(w.writer(), 1 << 20);
  for (std::uint64_t v = 1; v <= 50; ++v) {
    PreparedUpdate u = small_update(v % 2 ? "a" : "b", v, "deform");
    ASSERT_TRUE(pub.push(u));
  }
  PreparedUpdate bad = small_update("a", 51, "boom");
  ASSERT_TRUE(pub.push(bad));
  pub.wait_idle();
  ASSERT_EQ(w.written.size(), 50u);
  for (std::uint64_t v = 1; v <= 50; ++v) EXPECT_EQ(w.written[v - 1].second, v);
  EXPECT_NE(w.thread, std::this_thread::get_id());
  const UpdatePublisher::Counters c = pub.shutdown();
  EXPECT_EQ(c.published, 50u);
  EXPECT_EQ(c.failed, 1u);
  EXPECT_EQ(c.dropped, 0u);
  PreparedUpdate late = small_update("a", 52, "deform");
  EXPECT_FALSE(pub.push(late));
}

TEST(UpdatePublisher, RefusesBeyondTheBoundAndHandsBackContiguousIncrementalUpdates) {
  RecordingWriter w;
  w.set_hold(true);
  const std::size_t one = small_update("s", 1, "deform").bytes();
  UpdatePublisher pub(w.writer(), 3 * one);
  PreparedUpdate first = small_update("s", 1, "deform");
  ASSERT_TRUE(pub.push(first));  // taken by the (held) writer thread, or still queued
  // Fill the queue until it refuses; the refused update is left intact.
  std::uint64_t v = 2;
  for (;; ++v) {
    PreparedUpdate u = small_update("s", v, "deform");
    if (!pub.push(u)) {
      EXPECT_EQ(u.ids.size(), 10u);
      break;
    }
    ASSERT_LT(v, 10u) << "the bound was never reached";
  }
  EXPECT_LE(pub.queued_bytes(), 3 * one);
  // Not contiguous with the next version: nothing is handed back.
  EXPECT_TRUE(pub.take_pending("s", v + 1, {"deform"}).empty());
  // A cause not in the list: nothing.
  EXPECT_TRUE(pub.take_pending("s", v, {"remove"}).empty());
  const std::size_t queued = pub.queued_updates();
  std::vector<PreparedUpdate> back = pub.take_pending("s", v, {"deform"});
  ASSERT_EQ(back.size(), queued);
  EXPECT_EQ(back.back().version, v - 1);
  EXPECT_EQ(pub.queued_bytes(), 0u);
  // push_anyway ignores the bound.
  for (std::uint64_t k = 0; k < 5; ++k) EXPECT_TRUE(pub.push_anyway(small_update("t", k + 1, "deform")));
  EXPECT_GT(pub.queued_bytes(), 3 * one);
  w.set_hold(false);
  pub.wait_idle();
  EXPECT_EQ(pub.counters().taken_back, queued);
}

TEST(UpdatePublisher, ShutdownDrainsWithinTheDeadlineAndDropsTheRest) {
  {
    RecordingWriter w;
    UpdatePublisher pub(w.writer(), 1 << 20);
    for (std::uint64_t v = 1; v <= 20; ++v) ASSERT_TRUE(pub.push_anyway(small_update("s", v, "deform")));
    const UpdatePublisher::Counters c = pub.shutdown(std::chrono::milliseconds(5000));
    EXPECT_EQ(c.published, 20u);
    EXPECT_EQ(c.dropped, 0u);
    EXPECT_EQ(w.written.size(), 20u);
  }
  {
    RecordingWriter w;
    w.set_hold(true);
    UpdatePublisher pub(w.writer(), 1 << 20);
    for (std::uint64_t v = 1; v <= 5; ++v) ASSERT_TRUE(pub.push_anyway(small_update("s", v, "deform")));
    std::thread release([&] {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      w.set_hold(false);
    });
    const UpdatePublisher::Counters c = pub.shutdown(std::chrono::milliseconds(0));
    release.join();
    // The update being written when the deadline passed is finished; the others are dropped.
    EXPECT_EQ(c.published + c.dropped, 5u);
    EXPECT_GE(c.dropped, 4u);
  }
}

// --- handler ---------------------------------------------------------------------------------

class HandlerTest : public ::testing::Test {
 protected:
  Handler handler{HandlerConfig{4, 1000, 1}};
  RequestBuilder rb;
  std::vector<UpdateEvent> updates;
  std::uint64_t next_id = 1;

  std::shared_ptr<const Reply> send(surfeledit_proto_Op op, std::uint64_t id = 0) {
    return handler.handle(rb.make(op, id ? id : next_id++), updates);
  }

  // Opens session "s" and uploads n sphere surfels in chunks of 4.
  void load(std::size_t n) {
    ASSERT_EQ(send(surfeledit_proto_OP_OPEN_SESSION)->status, Status::Ok);
    rb.load_begin.total = n;
    rb.load_begin.has_radii = true;
    ASSERT_EQ(send(surfeledit_proto_OP_LOAD_BEGIN)->status, Status::Ok);
    for (std::size_t first = 0; first < n; first += 4) {
      ChunkArrays c = sphere_chunk(std::min<std::size_t>(4, n - first), first, n);
      rb.load_chunk.offset = first;
      point_to(rb.load_chunk.positions, c.positions);
      point_to(rb.load_chunk.normals, c.normals);
      point_to(rb.load_chunk.radii, c.radii);
      const auto r = send(surfeledit_proto_OP_LOAD_CHUNK);
      ASSERT_EQ(r->status, Status::Ok) << r->field << ": " << r->message;
    }
    const auto r = send(surfeledit_proto_OP_LOAD_COMMIT);
    ASSERT_EQ(r->status, Status::Ok) << r->field << ": " << r->message;
  }
};

TEST_F(HandlerTest, InfoWithoutSession) {
  const auto r = send(surfeledit_proto_OP_INFO);
  EXPECT_EQ(r->status, Status::Ok);
  ASSERT_TRUE(r->server_info);
  EXPECT_EQ(r->server_info->max_chunk_surfels, 4u);
  EXPECT_EQ(r->version, 0u);
  ASSERT_FALSE(r->timings.empty());
  EXPECT_EQ(r->timings.back().first, "total");
}

TEST_F(HandlerTest, CommitPublishesAFullUpdateAndBumpsTheVersion) {
  load(10);
  ASSERT_EQ(updates.size(), 1u);
  EXPECT_EQ(updates[0].cause, "load");
  EXPECT_TRUE(updates[0].full);
  EXPECT_EQ(updates[0].version, 1u);
  const SurfelModel* model = handler.model_of("s");
  ASSERT_NE(model, nullptr);
  EXPECT_EQ(model->size(), 10);
  EXPECT_EQ(update_parts(prepare_update(updates[0], model), 4), 3u);
}

TEST_F(HandlerTest, ARepeatedRequestIsAnsweredAgainNotReapplied) {
  load(8);
  rb.load_begin.total = 4;
  ASSERT_EQ(send(surfeledit_proto_OP_LOAD_BEGIN)->status, Status::Ok);
  ChunkArrays c = sphere_chunk(4);
  rb.load_chunk.offset = 0;
  point_to(rb.load_chunk.positions, c.positions);
  point_to(rb.load_chunk.normals, c.normals);
  point_to(rb.load_chunk.radii, c.radii);
  ASSERT_EQ(send(surfeledit_proto_OP_LOAD_CHUNK)->status, Status::Ok);
  const std::uint64_t commit_id = next_id++;
  const auto first = send(surfeledit_proto_OP_LOAD_COMMIT, commit_id);
  ASSERT_EQ(first->status, Status::Ok) << first->message;
  EXPECT_EQ(first->version, 2u);
  const std::size_t updates_after_first = updates.size();
  const auto again = send(surfeledit_proto_OP_LOAD_COMMIT, commit_id);
  EXPECT_EQ(again, first);  // the stored reply itself
  EXPECT_EQ(updates.size(), updates_after_first);  // nothing published again
  // A new id is a new request: there is no upload any more.
  const auto fresh = send(surfeledit_proto_OP_LOAD_COMMIT);
  EXPECT_EQ(fresh->status, Status::Conflict);
  EXPECT_EQ(fresh->version, 2u);
}

TEST_F(HandlerTest, ErrorsNameTheFieldAndChangeNothing) {
  load(8);
  const std::size_t n_updates = updates.size();
  // Missing argument sequence.
  surfeledit_proto_Request req = rb.make(surfeledit_proto_OP_DEFORM, next_id++);
  req.deform._length = 0;
  auto r = handler.handle(req, updates);
  EXPECT_EQ(r->status, Status::InvalidArgument);
  EXPECT_EQ(r->field, "deform");
  // Deform without regions: Conflict from the core, version unchanged.
  rb.deform.translation = {0, 0, 1};
  r = send(surfeledit_proto_OP_DEFORM);
  EXPECT_NE(r->status, Status::Ok);
  EXPECT_EQ(r->version, 1u);
  // Unknown op.
  req = rb.make(static_cast<surfeledit_proto_Op>(77), next_id++);
  r = handler.handle(req, updates);
  EXPECT_EQ(r->status, Status::InvalidArgument);
  EXPECT_EQ(r->field, "op");
  // Another client may not touch the session before joining it.
  rb.client = "client-b";
  r = send(surfeledit_proto_OP_GET_STATE);
  EXPECT_EQ(r->status, Status::Conflict);
  EXPECT_EQ(r->field, "session");
  rb.session = "nope";
  r = send(surfeledit_proto_OP_JOIN_SESSION);
  EXPECT_EQ(r->status, Status::NotFound);
  EXPECT_EQ(updates.size(), n_updates);
}

TEST_F(HandlerTest, StatePagesCoverTheModel) {
  load(10);
  rb.get_state = surfeledit_proto_GetState{};
  rb.get_state.max_count = 0;  // server limit: 4
  std::vector<std::uint64_t> ids;
  std::uint64_t total = 0;
  do {
    rb.get_state.offset = ids.size();
    const auto r = send(surfeledit_proto_OP_GET_STATE);
    ASSERT_EQ(r->status, Status::Ok) << r->message;
    ASSERT_TRUE(r->state);
    EXPECT_TRUE(r->state->full);
    EXPECT_LE(r->state->ids.size(), 4u);
    EXPECT_EQ(r->state->positions.size(), 3 * r->state->ids.size());
    total = r->state->total;
    ids.insert(ids.end(), r->state->ids.begin(), r->state->ids.end());
  } while (ids.size() < total);
  EXPECT_EQ(total, 10u);
  EXPECT_EQ(ids, handler.model_of("s")->ids());
  rb.get_state.offset = 11;
  EXPECT_EQ(send(surfeledit_proto_OP_GET_STATE)->field, "get_state.offset");
  // Nothing changed since the current version.
  rb.get_state = surfeledit_proto_GetState{};
  rb.get_state.changes_only = true;
  rb.get_state.since_version = 1;
  const auto r = send(surfeledit_proto_OP_GET_STATE);
  ASSERT_TRUE(r->state);
  EXPECT_EQ(r->state->total, 0u);
}

TEST_F(HandlerTest, TheLastCloseDropsTheSession) {
  ASSERT_EQ(send(surfeledit_proto_OP_OPEN_SESSION)->status, Status::Ok);
  rb.client = "client-b";
  ASSERT_EQ(send(surfeledit_proto_OP_JOIN_SESSION)->session_info->clients, 2u);
  ASSERT_EQ(send(surfeledit_proto_OP_CLOSE_SESSION)->status, Status::Ok);
  EXPECT_TRUE(updates.empty());
  rb.client = "client-a";
  ASSERT_EQ(send(surfeledit_proto_OP_CLOSE_SESSION)->status, Status::Ok);
  ASSERT_EQ(updates.size(), 1u);
  EXPECT_EQ(updates[0].cause, "close");
  const auto info = send(surfeledit_proto_OP_INFO);
  EXPECT_TRUE(info->server_info->sessions.empty());
  EXPECT_EQ(send(surfeledit_proto_OP_CLOSE_SESSION)->status, Status::Conflict);
}

// --- configure, remove, collision results ---------------------------------------------------

namespace {

// A plate of plane surfels at z = 0 (normals +z, n*n of them, spacing h) and a small sphere above
// it: the zero region is the plate, the one region the sphere.
ChunkArrays plate_and_ball(int n, double h, int ball, double ball_r, double ball_z) {
  ChunkArrays a;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const double p[3] = {(i - (n - 1) / 2.0) * h, (j - (n - 1) / 2.0) * h, 0.0};
      for (double v : p) a.positions.push_back(v);
      for (double v : {0.0, 0.0, 1.0}) a.normals.push_back(v);
      a.radii.push_back(0.75 * h);
    }
  }
  const ChunkArrays s = sphere_chunk(static_cast<std::size_t>(ball));
  for (int k = 0; k < ball; ++k) {
    for (int c = 0; c < 3; ++c) {
      const double u = s.positions[3 * k + c];
      a.positions.push_back(ball_r * u + (c == 2 ? ball_z : 0.0));
      a.normals.push_back(u);
    }
    a.radii.push_back(ball_r * 0.2);
  }
  return a;
}

Setting find_setting(const SessionInfo& info, const std::string& name) {
  for (const Setting& s : info.settings)
    if (s.name == name) return s;
  ADD_FAILURE() << "no setting " << name;
  return {};
}

}  // namespace

class CollisionHandlerTest : public HandlerTest {
 protected:
  static constexpr int kPlate = 15;  // 225 plate surfels, ids 0..224
  static constexpr int kBall = 200;  // ids 225..424
  ChunkArrays arrays = plate_and_ball(kPlate, 0.05, kBall, 0.15, 0.2);
  std::vector<std::uint64_t> zero_ids, one_ids;
  std::vector<surfeledit_proto_Setting> settings;
  std::vector<std::string> names, texts;  // storage of the settings' strings
  std::vector<std::uint64_t> remove_ids;
  surfeledit_proto_Configure configure{};
  surfeledit_proto_Remove remove{};

  void SetUp() override {
    const std::size_t n = arrays.radii.size();
    ASSERT_EQ(send(surfeledit_proto_OP_OPEN_SESSION)->status, Status::Ok);
    rb.load_begin.total = n;
    rb.load_begin.has_radii = true;
    ASSERT_EQ(send(surfeledit_proto_OP_LOAD_BEGIN)->status, Status::Ok);
    std::vector<double> pos, nrm, rad;  // one chunk (the handler's limit: 4 surfels)
    for (std::size_t first = 0; first < n; first += 4) {
      const std::size_t end = std::min<std::size_t>(n, first + 4);
      pos.assign(arrays.positions.begin() + 3 * first, arrays.positions.begin() + 3 * end);
      nrm.assign(arrays.normals.begin() + 3 * first, arrays.normals.begin() + 3 * end);
      rad.assign(arrays.radii.begin() + first, arrays.radii.begin() + end);
      rb.load_chunk.offset = first;
      point_to(rb.load_chunk.positions, pos);
      point_to(rb.load_chunk.normals, nrm);
      point_to(rb.load_chunk.radii, rad);
      ASSERT_EQ(send(surfeledit_proto_OP_LOAD_CHUNK)->status, Status::Ok);
    }
    const auto r = send(surfeledit_proto_OP_LOAD_COMMIT);
    ASSERT_EQ(r->status, Status::Ok) << r->field << ": " << r->message;
    for (std::uint64_t id = 0; id < n; ++id) (id < kPlate * kPlate ? zero_ids : one_ids).push_back(id);
    rb.set_regions = surfeledit_proto_SetRegions{};
    point_to(rb.set_regions.zero.ids, zero_ids);
    point_to(rb.set_regions.one.ids, one_ids);
    const auto regions = send(surfeledit_proto_OP_SET_REGIONS);
    ASSERT_EQ(regions->status, Status::Ok) << regions->field << ": " << regions->message;
    updates.clear();
  }

  // Sends OP_CONFIGURE with the given settings (text / number / bool by the value's type).
  std::shared_ptr<const Reply> configure_with(const std::vector<NamedSetting>& changes) {
    settings.clear();
    names.clear();
    texts.clear();
    names.reserve(changes.size());
    texts.reserve(changes.size());
    for (const NamedSetting& c : changes) {
      surfeledit_proto_Setting s{};
      names.push_back(c.name);
      s.name = const_cast<char*>(names.back().c_str());
      texts.push_back(std::holds_alternative<std::string>(c.value) ? std::get<std::string>(c.value) : "");
      s.text = const_cast<char*>(texts.back().c_str());
      if (std::holds_alternative<double>(c.value)) {
        s.kind = surfeledit_proto_SETTING_NUMBER;
        s.number = std::get<double>(c.value);
      } else if (std::holds_alternative<bool>(c.value)) {
        s.kind = surfeledit_proto_SETTING_BOOL;
        s.flag = std::get<bool>(c.value);
      } else {
        s.kind = surfeledit_proto_SETTING_TEXT;
      }
      settings.push_back(s);
    }
    point_to(configure.settings, settings);
    surfeledit_proto_Request req = rb.make(surfeledit_proto_OP_CONFIGURE, next_id++);
    req.configure._length = req.configure._maximum = 1;
    req.configure._buffer = &configure;
    return handler.handle(req, updates);
  }

  std::shared_ptr<const Reply> remove_these(std::vector<std::uint64_t> ids) {
    remove_ids = std::move(ids);
    point_to(remove.ids, remove_ids);
    surfeledit_proto_Request req = rb.make(surfeledit_proto_OP_REMOVE, next_id++);
    req.remove._length = req.remove._maximum = 1;
    req.remove._buffer = &remove;
    return handler.handle(req, updates);
  }

  std::shared_ptr<const Reply> info() { return send(surfeledit_proto_OP_INFO); }
};

TEST_F(CollisionHandlerTest, ConfigureAppliesEverySettingAndKeepsTheModel) {
  const auto before = info();
  ASSERT_TRUE(before->session_info);
  EXPECT_FALSE(before->session_info->settings.empty());
  EXPECT_EQ(find_setting(*before->session_info, "algorithm").text, "robust");
  const auto r = configure_with({{"algorithm", std::string("simple")}, {"boundary_n", 6.0}, {"step_bound", false}});
  ASSERT_EQ(r->status, Status::Ok) << r->field << ": " << r->message;
  ASSERT_TRUE(r->session_info);
  const Setting algorithm = find_setting(*r->session_info, "algorithm");
  EXPECT_EQ(algorithm.kind, SettingKind::Text);
  EXPECT_EQ(algorithm.text, "simple");
  EXPECT_EQ(find_setting(*r->session_info, "boundary_n").number, 6.0);
  EXPECT_EQ(find_setting(*r->session_info, "step_bound").kind, SettingKind::Bool);
  EXPECT_FALSE(find_setting(*r->session_info, "step_bound").flag);
  EXPECT_EQ(r->version, before->version);  // the model and version do not change
  EXPECT_EQ(r->session_info->state_hash, before->session_info->state_hash);
  EXPECT_TRUE(updates.empty());
  // The reply presents the settings with their kinds.
  const ReplyView view(*r);
  const auto& si = view.get()->session_info._buffer[0];
  ASSERT_EQ(si.settings._length, r->session_info->settings.size());
  bool seen = false;
  for (uint32_t i = 0; i < si.settings._length; ++i) {
    if (std::string(si.settings._buffer[i].name) == "algorithm") {
      seen = true;
      EXPECT_EQ(si.settings._buffer[i].kind, surfeledit_proto_SETTING_TEXT);
      EXPECT_STREQ(si.settings._buffer[i].text, "simple");
    }
  }
  EXPECT_TRUE(seen);
}

TEST_F(CollisionHandlerTest, ConfigureRejectsAtomicallyNamingTheSetting) {
  ASSERT_EQ(configure_with({{"boundary_n", 6.0}})->status, Status::Ok);
  const auto before = info();
  struct Case {
    std::vector<NamedSetting> changes;
    std::string field;
  };
  const std::vector<Case> cases = {
      {{{"boundary_n", 8.0}, {"algorithm", std::string("bogus")}}, "algorithm"},
      {{{"algorithm", std::string("simple")}, {"boundary_n", -1.0}}, "boundary_n"},
      {{{"algorithm", std::string("simple")}, {"boundary_n", std::string("ten")}}, "boundary_n"},
      {{{"boundary_n", 2.5}}, "boundary_n"},
      {{{"no_such_setting", 1.0}}, "no_such_setting"},
      {{{"boundary", 1.0}}, "boundary"},
  };
  for (const Case& c : cases) {
    const auto r = configure_with(c.changes);
    EXPECT_EQ(r->status, Status::InvalidArgument) << c.field;
    EXPECT_EQ(r->field, c.field) << r->message;
    EXPECT_FALSE(r->session_info);
  }
  // An unknown kind is refused before the core sees it, naming the setting.
  settings.assign(1, surfeledit_proto_Setting{});
  names = {"threshold"};
  settings[0].name = const_cast<char*>(names[0].c_str());
  settings[0].kind = static_cast<surfeledit_proto_SettingKind>(9);
  point_to(configure.settings, settings);
  surfeledit_proto_Request req = rb.make(surfeledit_proto_OP_CONFIGURE, next_id++);
  req.configure._length = req.configure._maximum = 1;
  req.configure._buffer = &configure;
  const auto bad_kind = handler.handle(req, updates);
  EXPECT_EQ(bad_kind->status, Status::InvalidArgument);
  EXPECT_EQ(bad_kind->field, "threshold");
  // Missing argument.
  req.configure._length = 0;
  req.request_id = next_id++;
  EXPECT_EQ(handler.handle(req, updates)->field, "configure");

  const auto after = info();
  EXPECT_EQ(after->version, before->version);
  EXPECT_EQ(after->session_info->state_hash, before->session_info->state_hash);
  ASSERT_EQ(after->session_info->settings.size(), before->session_info->settings.size());
  for (std::size_t i = 0; i < after->session_info->settings.size(); ++i) {
    const Setting& a = after->session_info->settings[i];
    const Setting& b = before->session_info->settings[i];
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.number, b.number) << a.name;
    EXPECT_EQ(a.flag, b.flag) << a.name;
    EXPECT_EQ(a.text, b.text) << a.name;
  }
  EXPECT_EQ(find_setting(*after->session_info, "algorithm").text, "robust");
  EXPECT_EQ(find_setting(*after->session_info, "boundary_n").number, 6.0);
  EXPECT_TRUE(updates.empty());
}

TEST_F(CollisionHandlerTest, RemoveValidatesFirstThenPublishesTheRemovedIds) {
  const auto before = info();
  const std::uint64_t v0 = before->version;
  // Unknown id (with a valid one): NotFound, nothing removed.
  auto r = remove_these({3, 99999});
  EXPECT_EQ(r->status, Status::NotFound);
  EXPECT_EQ(r->field.rfind("remove", 0), 0u) << r->field;
  // Emptying the one region: Conflict.
  r = remove_these(one_ids);
  EXPECT_EQ(r->status, Status::Conflict) << r->field << ": " << r->message;
  EXPECT_EQ(info()->session_info->state_hash, before->session_info->state_hash);
  EXPECT_EQ(info()->version, v0);
  EXPECT_TRUE(updates.empty());

  r = remove_these({5, 300, 3});
  ASSERT_EQ(r->status, Status::Ok) << r->field << ": " << r->message;
  EXPECT_EQ(r->version, v0 + 1);
  ASSERT_TRUE(r->session_info);
  EXPECT_EQ(r->session_info->surfels, before->session_info->surfels - 3);
  ASSERT_EQ(updates.size(), 1u);
  EXPECT_EQ(updates[0].cause, "remove");
  EXPECT_EQ(updates[0].version, v0 + 1);
  EXPECT_EQ(updates[0].removed, (IdList{3, 5, 300}));
  EXPECT_FALSE(updates[0].full);
  // Ids stay stable: the remaining ones are what they were.
  const SurfelModel* model = handler.model_of("s");
  EXPECT_EQ(model->row_of(3), -1);
  EXPECT_GE(model->row_of(4), 0);
  EXPECT_EQ(model->ids()[static_cast<std::size_t>(model->row_of(424))], 424u);
  // A repeat is answered from the cache.
  surfeledit_proto_Request req = rb.make(surfeledit_proto_OP_REMOVE, next_id - 1);
  req.remove._length = req.remove._maximum = 1;
  req.remove._buffer = &remove;
  EXPECT_EQ(handler.handle(req, updates), r);
  EXPECT_EQ(updates.size(), 1u);
}

TEST_F(CollisionHandlerTest, StepInfoAndTheUpdateCarryTheCollisionResult) {
  // In-process oracle: the same model, regions, settings and steps.
  EditSession oracle("oracle", SessionParams{1});
  {
    SurfelArrays a;
    const std::size_t n = arrays.radii.size();
    a.positions = Eigen::Map<const Points>(arrays.positions.data(), static_cast<Eigen::Index>(n), 3);
    a.normals = Eigen::Map<const Points>(arrays.normals.data(), static_cast<Eigen::Index>(n), 3);
    a.radii = Eigen::Map<const Values>(arrays.radii.data(), static_cast<Eigen::Index>(n));
    oracle.load(SurfelModel::from_arrays(a));
    RegionSpec zero, one;
    zero.ids = zero_ids;
    one.ids = one_ids;
    oracle.set_regions(zero, one);
  }
  for (const char* algorithm : {"robust", "simple"}) {
    ASSERT_EQ(configure_with({{"algorithm", std::string(algorithm)}})->status, Status::Ok);
    oracle.configure({{"algorithm", std::string(algorithm)}});
    std::size_t with_collisions = 0;
    for (int i = 0; i < 4; ++i) {
      updates.clear();
      rb.deform = surfeledit_proto_Deform{};
      rb.deform.translation = {0.0, 0.0, -0.06};
      rb.deform.axis = {0.0, 0.0, 1.0};
      rb.blend = "linear";
      const auto r = send(surfeledit_proto_OP_DEFORM);
      ASSERT_EQ(r->status, Status::Ok) << r->field << ": " << r->message;
      DeformParams p;
      p.translation = Vec3(0.0, 0.0, -0.06);
      p.axis = Vec3(0.0, 0.0, 1.0);
      p.blend = Blend::Linear;
      const StepOutcome expected = oracle.deform(p);

      ASSERT_TRUE(r->step);
      const StepInfo& st = *r->step;
      EXPECT_TRUE(st.detected);
      EXPECT_EQ(st.colliding, expected.colliding) << algorithm << " step " << i;
      EXPECT_TRUE(std::is_sorted(st.colliding.begin(), st.colliding.end()));
      ASSERT_EQ(st.depths.size(), st.colliding.size());
      for (double d : st.depths) EXPECT_GE(d, 0.0);
      EXPECT_EQ(st.stats.colliding, st.colliding.size());
      EXPECT_EQ(st.stats.deformable, static_cast<std::uint64_t>(expected.stats.deformable));
      EXPECT_EQ(st.stats.queries, static_cast<std::uint64_t>(expected.stats.queries));
      EXPECT_EQ(st.inserted, expected.inserted);
      for (std::uint64_t id : st.colliding) EXPECT_GE(id, static_cast<std::uint64_t>(kPlate * kPlate));
      if (!st.colliding.empty()) ++with_collisions;

      ASSERT_EQ(updates.size(), 1u);
      EXPECT_EQ(updates[0].cause, "deform");
      EXPECT_TRUE(updates[0].detected);
      EXPECT_EQ(updates[0].colliding, st.colliding);
      EXPECT_EQ(updates[0].step, st.seq);
      const PreparedUpdate u = prepare_update(updates[0], handler.model_of("s"));
      const UpdateView v(update_chunk(u, 0, 1000));
      EXPECT_TRUE(v.get()->detected);
      EXPECT_EQ(v.get()->colliding._length, st.colliding.size());

      // The reply presents every collision field.
      const ReplyView rv(*r);
      const surfeledit_proto_StepInfo& ps = rv.get()->step._buffer[0];
      EXPECT_EQ(ps.detected, st.detected);
      EXPECT_EQ(ps.colliding._length, st.colliding.size());
      EXPECT_EQ(ps.depths._length, st.depths.size());
      EXPECT_EQ(ps.stats.queries, st.stats.queries);
      EXPECT_EQ(ps.stats.colliding, st.stats.colliding);
    }
    EXPECT_GT(with_collisions, 0u) << algorithm << ": the ball never reached the plate";
    // Move back up for the next algorithm (configure re-initialises from the current model).
    rb.deform = surfeledit_proto_Deform{};
    rb.deform.translation = {0.0, 0.0, 0.24};
    rb.deform.axis = {0.0, 0.0, 1.0};
    ASSERT_EQ(send(surfeledit_proto_OP_DEFORM)->status, Status::Ok);
    DeformParams up;
    up.translation = Vec3(0.0, 0.0, 0.24);
    up.axis = Vec3(0.0, 0.0, 1.0);
    up.blend = Blend::Linear;
    oracle.deform(up);
  }
  // Algorithm none: nothing detected, no collision state in the update.
  ASSERT_EQ(configure_with({{"algorithm", std::string("none")}})->status, Status::Ok);
  updates.clear();
  const auto r = send(surfeledit_proto_OP_DEFORM);
  ASSERT_EQ(r->status, Status::Ok);
  EXPECT_FALSE(r->step->detected);
  EXPECT_TRUE(r->step->colliding.empty());
  ASSERT_EQ(updates.size(), 1u);
  EXPECT_FALSE(updates[0].detected);
}
