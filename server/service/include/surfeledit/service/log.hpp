// The one logger of the service library, named "surfeledit".
#pragma once

#include <spdlog/spdlog.h>

#include <memory>

namespace surfeledit::service {

// The registered "surfeledit" logger; created (colour stderr sink) on first use if the
// application did not register one itself.
std::shared_ptr<spdlog::logger> logger();

}  // namespace surfeledit::service
