// Service pieces that need no network: request cache, uploads, conversions, update chunks,
// and the request handler (idempotence, atomicity, paging) driven with generated C requests.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "surfeledit/service/convert.hpp"
#include "surfeledit/service/handler.hpp"
#include "surfeledit/service/request_cache.hpp"
#include "surfeledit/service/update.hpp"
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

TEST(Update, ChunksChangedRows) {
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
  ASSERT_EQ(update_parts(all, &model, 2), 3u);
  const UpdateChunk last = build_update_chunk(all, &model, 2, 2);
  EXPECT_EQ(last.part, 2u);
  EXPECT_EQ(last.parts, 3u);
  ASSERT_EQ(last.ids.size(), 1u);
  EXPECT_EQ(last.ids[0], model.ids()[4]);
  EXPECT_DOUBLE_EQ(last.positions[2], model.positions()(4, 2));
  EXPECT_TRUE(last.removed.empty());
  EXPECT_EQ(build_update_chunk(all, &model, 0, 2).removed, std::vector<std::uint64_t>{99});

  UpdateEvent some;
  some.cause = "deform";
  some.rows = {1, 3};
  ASSERT_EQ(update_parts(some, &model, 65536), 1u);
  const UpdateChunk one = build_update_chunk(some, &model, 0, 65536);
  EXPECT_EQ(one.ids, (std::vector<std::uint64_t>{model.ids()[1], model.ids()[3]}));
  EXPECT_EQ(one.radii.size(), 2u);

  UpdateEvent close;
  close.cause = "close";
  EXPECT_EQ(update_parts(close, nullptr, 2), 1u);
  EXPECT_TRUE(build_update_chunk(close, nullptr, 0, 2).ids.empty());
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
  EXPECT_EQ(update_parts(updates[0], model, 4), 3u);
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
