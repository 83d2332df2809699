#include "file_loads.hpp"

#include <algorithm>

namespace surfeledit::service {

void FileLoads::set_on_done(std::function<void()> on_done) {
  std::lock_guard<std::mutex> lock(mutex_);
  on_done_ = std::move(on_done);
}

FileLoads::~FileLoads() {
  std::list<Job> jobs;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    jobs.splice(jobs.end(), jobs_);
  }
  for (Job& job : jobs)
    if (job.thread.joinable()) job.thread.join();
}

bool FileLoads::pending(const std::string& client_id, std::uint64_t request_id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return std::any_of(jobs_.begin(), jobs_.end(), [&](const Job& j) {
    return j.load.client_id == client_id && j.load.request_id == request_id;
  });
}

bool FileLoads::busy(const std::string& session) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return std::any_of(jobs_.begin(), jobs_.end(), [&](const Job& j) { return j.load.session == session; });
}

bool FileLoads::idle() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return jobs_.empty();
}

std::size_t FileLoads::running() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return static_cast<std::size_t>(std::count_if(jobs_.begin(), jobs_.end(), [](const Job& j) { return !j.done; }));
}

void FileLoads::start(FileLoad load, std::function<SurfelArrays()> work) {
  std::lock_guard<std::mutex> lock(mutex_);
  jobs_.push_back(Job{std::move(load), false, {}});
  Job* job = &jobs_.back();
  job->thread = std::thread([this, job, work = std::move(work)] {
    std::optional<SurfelArrays> arrays;
    std::exception_ptr error;
    try {
      arrays = work();
    } catch (...) {
      error = std::current_exception();
    }
    {
      std::lock_guard<std::mutex> done_lock(mutex_);
      job->load.arrays = std::move(arrays);
      job->load.error = error;
      job->done = true;
      finished_.push_back(job);
      try {
        if (on_done_) on_done_();  // under the lock: set_on_done({}) guarantees no later call
      } catch (...) {
        // A failed wake-up: the request thread still collects this load at its next wake-up.
      }
    }
  });
}

std::vector<FileLoad> FileLoads::take_finished() {
  std::vector<FileLoad> out;
  std::list<Job> done;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (Job* job : finished_) {
      out.push_back(std::move(job->load));
      const auto it = std::find_if(jobs_.begin(), jobs_.end(), [job](const Job& j) { return &j == job; });
      done.splice(done.end(), jobs_, it);
    }
    finished_.clear();
  }
  for (Job& job : done) job.thread.join();  // the worker has left its critical section (or is leaving it)
  return out;
}

}  // namespace surfeledit::service
