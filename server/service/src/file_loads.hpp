// File loads off the request thread (OP_LOAD_FILE, docs/hardening.md "Files"): reading and parsing a
// file (and estimating its normals) runs on a worker thread per load, so one slow file never stalls the
// other clients. The request thread starts a load, keeps serving, and later collects the finished ones
// (take_finished) to commit them and send their replies; `on_done` tells it one is ready.
#pragma once

#include <chrono>
#include <cstdint>
#include <exception>
#include <functional>
#include <list>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "surfeledit/core/surfel_model.hpp"

namespace surfeledit::service {

// One load: who asked, and (when finished) what came of it.
struct FileLoad {
  std::string client_id;
  std::uint64_t request_id = 0;
  std::string session;
  std::chrono::steady_clock::time_point started;  // when the request arrived
  std::optional<SurfelArrays> arrays;              // finished without error
  std::exception_ptr error;                        // finished with an error
};

class FileLoads {
 public:
  static constexpr std::size_t kMaxRunning = 2;  // loads at once (each may hold a model's worth of memory)

  FileLoads() = default;
  ~FileLoads();  // waits for the running loads (each bounded by the file size limit)
  FileLoads(const FileLoads&) = delete;
  FileLoads& operator=(const FileLoads&) = delete;

  // Called on the worker thread after a load finished (e.g. to wake the request thread), under the
  // table's lock: it must be quick and must not call back into this object. Empty: no call.
  void set_on_done(std::function<void()> on_done);

  // Whether request (client_id, request_id) is loading (a repeat of it gets no second reply or load).
  bool pending(const std::string& client_id, std::uint64_t request_id) const;
  // Whether a load into `session` is running or waits to be collected.
  bool busy(const std::string& session) const;
  std::size_t running() const;
  // Whether no load is running or waits to be collected.
  bool idle() const;

  // Runs `work` on a new thread for `load` (the caller checked busy() and running()).
  void start(FileLoad load, std::function<SurfelArrays()> work);
  // The finished loads, in the order they finished; their threads are joined.
  std::vector<FileLoad> take_finished();

 private:
  struct Job {
    FileLoad load;
    bool done = false;
    std::thread thread;
  };
  mutable std::mutex mutex_;
  std::list<Job> jobs_;  // stable addresses: a worker writes into its own Job
  std::vector<Job*> finished_;
  std::function<void()> on_done_;
};

}  // namespace surfeledit::service
