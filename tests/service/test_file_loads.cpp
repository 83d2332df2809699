// OP_LOAD_FILE: the data root's checks, and loads that finish off the request thread with exactly one
// reply each (Handler::finish_loads), never a second load for a repeated request id.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <set>
#include <thread>

#include "../../server/service/src/data_root.hpp"
#include "handler_fixture.hpp"
#include "surfeledit/core/model_io.hpp"

using namespace surfeledit;
using namespace surfeledit::service;
using namespace surfeledit::service::test;

namespace {

namespace fs = std::filesystem;

fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("surfeledit_loads_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

SurfelArrays cloud(int n) {
  SurfelArrays a;
  a.positions.resize(n, 3);
  a.normals.resize(n, 3);
  for (int i = 0; i < n; ++i) {
    a.positions.row(i) << i, 0.5 * i, 0.0;
    a.normals.row(i) << 0.0, 0.0, 1.0;
  }
  a.radii = Values::Constant(n, 0.25);
  return a;
}

Error error_of(const DataRoot& root, const std::string& path) {
  try {
    root.resolve(path);
  } catch (const Error& e) {
    return e;
  }
  ADD_FAILURE() << "no error for " << path;
  return Error(ErrorCode::Internal, "", "");
}

class FileLoadTest : public ::testing::Test {
 protected:
  fs::path dir = fresh_dir(::testing::UnitTest::GetInstance()->current_test_info()->name());
  fs::path root = dir / "root";
  Handler handler{make_config()};
  RequestBuilder rb;
  surfeledit_proto_LoadFile load_file{};
  std::string file_path;
  std::vector<UpdateEvent> updates;

  HandlerConfig make_config() {
    fs::create_directories(root);
    HandlerConfig c{4, 1000, 1};
    c.data_root = root.string();
    return c;
  }
  ~FileLoadTest() override { fs::remove_all(dir); }

  std::shared_ptr<const Reply> send(surfeledit_proto_Op op, std::uint64_t id, const std::string& path = "") {
    surfeledit_proto_Request req = rb.make(op, id);
    if (op == surfeledit_proto_OP_LOAD_FILE) {
      file_path = path;
      load_file.path = const_cast<char*>(file_path.c_str());
      req.load_file._length = req.load_file._maximum = 1;
      req.load_file._buffer = &load_file;
    }
    return handler.handle(decode(req), updates);
  }

  // The replies of loads that finish within 10 s (polling), at least `want` of them.
  std::vector<std::shared_ptr<const Reply>> wait_replies(std::size_t want) {
    std::vector<std::shared_ptr<const Reply>> out;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (out.size() < want && std::chrono::steady_clock::now() < deadline) {
      for (auto& r : handler.finish_loads(updates)) out.push_back(r);
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return out;
  }
};

TEST_F(FileLoadTest, ALoadRepliesLaterExactlyOnceAndARepeatNeverLoadsTwice) {
  save_surfels((root / "c.ply").string(), cloud(30));
  ASSERT_EQ(send(surfeledit_proto_OP_OPEN_SESSION, 1)->status, Status::Ok);
  updates.clear();  // the presence update of the open
  EXPECT_EQ(send(surfeledit_proto_OP_LOAD_FILE, 2, "c.ply"), nullptr);  // replies later
  EXPECT_EQ(send(surfeledit_proto_OP_LOAD_FILE, 2, "c.ply"), nullptr);  // a repeat: still that one load
  // A second load into the same session while the first is not committed.
  const auto busy = send(surfeledit_proto_OP_LOAD_FILE, 3, "c.ply");
  ASSERT_NE(busy, nullptr);
  EXPECT_EQ(busy->status, Status::Conflict);
  EXPECT_EQ(busy->field, "load_file");
  const auto replies = wait_replies(1);
  ASSERT_EQ(replies.size(), 1u);
  EXPECT_EQ(replies[0]->request_id, 2u);
  ASSERT_EQ(replies[0]->status, Status::Ok) << replies[0]->field << ": " << replies[0]->message;
  EXPECT_EQ(replies[0]->version, 1u);
  ASSERT_TRUE(replies[0]->session_info);
  EXPECT_EQ(replies[0]->session_info->surfels, 30u);
  ASSERT_EQ(updates.size(), 1u);
  EXPECT_TRUE(updates[0].full);
  EXPECT_TRUE(handler.finish_loads(updates).empty());
  EXPECT_EQ(send(surfeledit_proto_OP_LOAD_FILE, 2, "c.ply"), replies[0]);  // now answered from the cache
  EXPECT_EQ(handler.model_of("s")->size(), 30);
}

TEST_F(FileLoadTest, AClientThatLeftMeanwhileGetsAnErrorReplyAndNothingIsLoaded) {
  save_surfels((root / "c.ply").string(), cloud(10));
  ASSERT_EQ(send(surfeledit_proto_OP_OPEN_SESSION, 1)->status, Status::Ok);
  EXPECT_EQ(send(surfeledit_proto_OP_LOAD_FILE, 2, "c.ply"), nullptr);
  ASSERT_EQ(send(surfeledit_proto_OP_CLOSE_SESSION, 3)->status, Status::Ok);
  const auto replies = wait_replies(1);
  ASSERT_EQ(replies.size(), 1u);
  EXPECT_NE(replies[0]->status, Status::Ok);
  EXPECT_FALSE(replies[0]->field.empty());
  for (const UpdateEvent& u : updates) EXPECT_NE(u.cause, "load");  // only the close was published
}

TEST_F(FileLoadTest, ReadErrorsComeBackInTheDeferredReplyWithoutTheResolvedPath) {
  std::ofstream(root / "bad.ply") << "ply\nformat ascii 1.0\nelement vertex 99\nproperty float x\nend_header\n1\n";
  ASSERT_EQ(send(surfeledit_proto_OP_OPEN_SESSION, 1)->status, Status::Ok);
  EXPECT_EQ(send(surfeledit_proto_OP_LOAD_FILE, 2, "bad.ply"), nullptr);
  const auto replies = wait_replies(1);
  ASSERT_EQ(replies.size(), 1u);
  EXPECT_EQ(replies[0]->status, Status::Io);
  EXPECT_EQ(replies[0]->field, "load_file.path");
  EXPECT_NE(replies[0]->message.find("'bad.ply'"), std::string::npos) << replies[0]->message;
  EXPECT_EQ(replies[0]->message.find(root.string()), std::string::npos) << replies[0]->message;
  EXPECT_EQ(replies[0]->version, 0u);
}

TEST(DataRoot, OneErrorForOutsideSymlinkDotDotAndMissing) {
  const fs::path dir = fresh_dir("data_root");
  fs::create_directories(dir / "root");
  fs::create_directories(dir / "outside");
  std::ofstream(dir / "outside" / "secret.ply") << "ply\n";
  std::ofstream(dir / "root" / "in.ply") << "ply\n";
  fs::create_symlink(dir / "outside" / "secret.ply", dir / "root" / "link.ply");
  ASSERT_EQ(::mkfifo((dir / "root" / "x.ply").c_str(), 0600), 0);
  const DataRoot root((dir / "root").string(), 1 << 20);
  EXPECT_EQ(root.resolve("in.ply"), fs::canonical(dir / "root" / "in.ply").string());
  std::set<std::string> messages;
  for (const std::string& p : {(dir / "outside" / "secret.ply").string(), std::string("link.ply"),
                               std::string("../outside/secret.ply"), std::string("missing.ply"),
                               (dir / "outside" / "missing.ply").string()}) {
    const Error e = error_of(root, p);
    EXPECT_EQ(e.code(), ErrorCode::NotFound) << p;
    EXPECT_EQ(e.field(), "load_file.path");
    std::string m = e.what();
    m.replace(m.find(p), p.size(), "<p>");
    messages.insert(m);
  }
  EXPECT_EQ(messages.size(), 1u) << *messages.begin();
  EXPECT_EQ(error_of(root, "x.ply").code(), ErrorCode::InvalidArgument);  // a FIFO: refused, not opened for data
  EXPECT_EQ(error_of(root, "notes.txt").code(), ErrorCode::InvalidArgument);
  const DataRoot tiny((dir / "root").string(), 2);
  EXPECT_EQ(error_of(tiny, "in.ply").code(), ErrorCode::TooLarge);
  const DataRoot off("", 1 << 20);
  EXPECT_EQ(error_of(off, "in.ply").code(), ErrorCode::Conflict);
  EXPECT_THROW(DataRoot((dir / "root" / "in.ply").string(), 1), std::invalid_argument);
  fs::remove_all(dir);
}

}  // namespace
