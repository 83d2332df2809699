// The edit ops against a session with a plate and a ball: CONFIGURE, REMOVE, DEFORM with its
// collision result.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <string>
#include <variant>
#include <vector>

#include "handler_fixture.hpp"
#include "surfeledit/service/sample_views.hpp"

using namespace surfeledit;
using namespace surfeledit::service;
using namespace surfeledit::service::test;

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
    return handler.handle(decode(req), updates);
  }

  std::shared_ptr<const Reply> remove_these(std::vector<std::uint64_t> ids) {
    remove_ids = std::move(ids);
    point_to(remove.ids, remove_ids);
    surfeledit_proto_Request req = rb.make(surfeledit_proto_OP_REMOVE, next_id++);
    req.remove._length = req.remove._maximum = 1;
    req.remove._buffer = &remove;
    return handler.handle(decode(req), updates);
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
  const auto bad_kind = handler.handle(decode(req), updates);
  EXPECT_EQ(bad_kind->status, Status::InvalidArgument);
  EXPECT_EQ(bad_kind->field, "threshold");
  // Missing argument.
  req.configure._length = 0;
  req.request_id = next_id++;
  EXPECT_EQ(handler.handle(decode(req), updates)->field, "configure");

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
  EXPECT_EQ(model->id_of(model->row_of(424)), 424u);
  // A repeat is answered from the cache.
  surfeledit_proto_Request req = rb.make(surfeledit_proto_OP_REMOVE, next_id - 1);
  req.remove._length = req.remove._maximum = 1;
  req.remove._buffer = &remove;
  EXPECT_EQ(handler.handle(decode(req), updates), r);
  EXPECT_EQ(updates.size(), 1u);
}

TEST_F(CollisionHandlerTest, StepResultAndTheUpdateCarryTheCollisionResult) {
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
      const surfeledit::StepResult expected = oracle.deform(p);

      ASSERT_TRUE(r->step);
      const service::StepResult& st = *r->step;
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
      const surfeledit_proto_StepResult& ps = rv.get()->step._buffer[0];
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
