#include "surfeledit/service/log.hpp"

#include <spdlog/sinks/stdout_color_sinks.h>

#include <mutex>

namespace surfeledit::service {

std::shared_ptr<spdlog::logger> logger() {
  static std::mutex mutex;
  std::lock_guard<std::mutex> lock(mutex);
  if (auto existing = spdlog::get("surfeledit")) return existing;
  return spdlog::stderr_color_mt("surfeledit");
}

}  // namespace surfeledit::service
