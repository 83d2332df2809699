// The surfeledit DDS service: serves Request samples from clients with one Reply each and
// publishes Update samples after every change (topics and semantics: proto/PROTOCOL.md).
//
// DDS stays behind the pimpl; this header needs nothing but the standard library.
#pragma once

#include <cstdint>
#include <memory>

namespace surfeledit::service {

struct ServiceConfig {
  int domain = 0;                                // DDS domain id of all three topics
  std::uint64_t max_chunk_surfels = 65536;       // surfels per LoadChunk, StatePage and Update sample
  std::uint64_t max_model_surfels = 20'000'000;  // surfels per model (LOAD_BEGIN total, loaded files)
  int threads = 0;                               // worker threads per session for batch work; 0 = all cores
};

class Service {
 public:
  // Creates the participant, topics, reader and writers; throws std::runtime_error on DDS
  // failures and std::invalid_argument on a bad config.
  explicit Service(ServiceConfig config);
  ~Service();
  Service(const Service&) = delete;
  Service& operator=(const Service&) = delete;

  // Serves requests until stop() is called (blocks on a waitset; never polls).
  void run();
  // Makes run() return after the request in progress; callable from any thread, also before run().
  void stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace surfeledit::service
