// A ServiceConfig (the server's settings, service.hpp) checked against its bounds and turned into
// the request handler's HandlerConfig.
#pragma once

#include "surfeledit/service/handler.hpp"
#include "surfeledit/service/service.hpp"

namespace surfeledit::service {

// The handler's settings of `c`; throws std::invalid_argument naming the first setting out of its
// bounds (or a combination of settings the server does not support).
HandlerConfig handler_config(const ServiceConfig& c);

}  // namespace surfeledit::service
