// A request's head as the transport reads it, shared by the server (http_server.cc) and the
// http_request fuzz target so both run the same checks: Beast parses, then these decide what
// Service sees or which answer refuses the request before any of its body is read.
#pragma once

#include <boost/beast/http/message.hpp>

#include <optional>
#include <string>

#include "config.h"
#include "service.h"

namespace pointdag::server {

using RequestHead = boost::beast::http::request_header<>;

// Header names in lower case; a field sent twice is combined with ", " (RFC 9110 5.3).
HttpRequest ToRequest(const RequestHead& head);

struct Refusal {
  int status;
  std::string message;
};
// Framing the transport will not guess at (each answered, then the connection closes):
// Transfer-Encoding other than exactly "chunked", or together with Content-Length (request
// smuggling behind a proxy); more header fields than the limit.
std::optional<Refusal> CheckHead(const RequestHead& head, const HttpLimits& limits);

}  // namespace pointdag::server
