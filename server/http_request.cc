#include "http_request.h"

#include <boost/beast/http/field.hpp>

#include <cctype>

namespace pointdag::server {
namespace http = boost::beast::http;

HttpRequest ToRequest(const RequestHead& head) {
  HttpRequest request;
  request.method = std::string(head.method_string());
  request.target = std::string(head.target());
  for (const auto& field : head) {
    std::string name(field.name_string());
    for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    const auto [it, inserted] = request.headers.try_emplace(name, field.value());
    if (!inserted) it->second += ", " + std::string(field.value());
  }
  return request;
}

std::optional<Refusal> CheckHead(const RequestHead& head, const HttpLimits& limits) {
  size_t fields = 0;
  for (auto it = head.begin(); it != head.end(); ++it) ++fields;
  if (fields > limits.max_header_fields) {
    return Refusal{431, "the request has " + std::to_string(fields) + " header fields; at most " +
                            std::to_string(limits.max_header_fields) + " are read"};
  }
  std::string coding;
  size_t codings = 0;
  for (auto [it, end] = head.equal_range(http::field::transfer_encoding); it != end; ++it) {
    coding = std::string(it->value());
    ++codings;
  }
  if (codings == 0) return std::nullopt;
  for (char& c : coding) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (codings > 1 || coding != "chunked") {
    return Refusal{400, "Transfer-Encoding must be exactly 'chunked' (no other coding is accepted)"};
  }
  if (head.count(http::field::content_length) > 0) {
    return Refusal{400, "a request may not carry both Transfer-Encoding and Content-Length"};
  }
  return std::nullopt;
}

}  // namespace pointdag::server
