// request_helpers.cpp — reading bearer tokens, media types, JSON bodies, Idempotency-Keys and
// query parameters (request_helpers.h).
#include "manipid/api/problem.h"

#include "json_fields.h"  // includes Eigen: before httplib.h

#include "http/request_helpers.h"  // includes httplib.h, after the manipid headers

#include <openssl/evp.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <initializer_list>
#include <memory>
#include <stdexcept>
#include <string_view>

namespace manipid::api::http {

std::string sha256_hex(std::initializer_list<std::string_view> parts) {
  const std::unique_ptr<EVP_MD_CTX, decltype(&EVP_MD_CTX_free)> context(EVP_MD_CTX_new(), EVP_MD_CTX_free);
  bool ok = context && EVP_DigestInit_ex(context.get(), EVP_sha256(), nullptr) == 1;
  for (const std::string_view part : parts) ok = ok && EVP_DigestUpdate(context.get(), part.data(), part.size()) == 1;
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  if (!ok || EVP_DigestFinal_ex(context.get(), digest, &length) != 1) throw std::runtime_error("SHA-256 failed");
  static const char* hex = "0123456789abcdef";
  std::string out;
  for (unsigned int i = 0; i < length; ++i) {
    out += hex[digest[i] >> 4];
    out += hex[digest[i] & 15];
  }
  return out;
}

bool token_matches(const std::string& given, const std::string& expected) {
  if (given.size() != expected.size()) return false;
  unsigned char difference = 0;
  for (std::size_t i = 0; i < given.size(); ++i) difference |= static_cast<unsigned char>(given[i] ^ expected[i]);
  return difference == 0;
}

std::optional<Caller> identify(const RouteState& state, const httplib::Request& request) {
  if (state.credentials.empty()) return Caller{};
  const std::string header = request.get_header_value("Authorization");
  const std::string prefix = "Bearer ";
  if (header.rfind(prefix, 0) != 0) return std::nullopt;
  // The digests all have one length, and every one is compared: how long this takes tells
  // nothing of the token given, of the tokens taken, or of which one matched.
  const std::string digest = sha256_hex({std::string_view(header).substr(prefix.size())});
  const Credential* found = nullptr;
  for (const Credential& credential : state.credentials) {
    if (token_matches(digest, credential.digest)) found = &credential;
  }
  if (found == nullptr) return std::nullopt;
  return found->caller;
}

Caller caller_of(const RouteState& state, const httplib::Request& request) {
  if (auto caller = identify(state, request)) return *caller;
  throw ApiError(ProblemKind::unauthorized, "this server needs 'Authorization: Bearer <token>'", "Authorization");
}


std::string media_type(const httplib::Request& request) {
  std::string type = request.get_header_value("Content-Type");
  type = type.substr(0, type.find(';'));
  type.erase(std::remove_if(type.begin(), type.end(), [](unsigned char c) { return std::isspace(c); }), type.end());
  std::transform(type.begin(), type.end(), type.begin(), [](unsigned char c) { return std::tolower(c); });
  return type;
}

bool looks_like_json(const std::string& body) {
  const auto first = body.find_first_not_of(" \t\r\n");
  return first != std::string::npos && (body[first] == '{' || body[first] == '[');
}

const std::string& json_text(const httplib::Request& request) {
  const std::string type = media_type(request);
  if (!(type == "application/json" || type.empty() || type == "application/x-www-form-urlencoded" ||
        (type.size() > 5 && type.compare(type.size() - 5, 5, "+json") == 0))) {
    throw ApiError(ProblemKind::unsupported_media, "expected Content-Type application/json, got " + type, "Content-Type");
  }
  if (request.body.empty()) throw ApiError(ProblemKind::malformed_body, "the request body is empty; expected a JSON object", "body");
  return request.body;
}

nlohmann::json json_body(const httplib::Request& request) {
  using Json = nlohmann::json;
  const Json body = fields::parse_request(json_text(request));  // no duplicate keys, short details
  if (!body.is_object()) throw ApiError(ProblemKind::malformed_body, "expected a JSON object at the top level", "body");
  return body;
}

std::optional<IdempotencyKey> idempotency_key(const httplib::Request& request) {
  if (!request.has_header("Idempotency-Key")) return std::nullopt;
  std::string key = request.get_header_value("Idempotency-Key");
  if (key.size() >= 2 && key.front() == '"' && key.back() == '"') key = key.substr(1, key.size() - 2);  // sf-string
  const bool printable = std::all_of(key.begin(), key.end(), [](unsigned char c) { return c > 32 && c < 127; });
  if (key.empty() || key.size() > 255 || !printable) {
    throw ApiError(ProblemKind::invalid_field, "Idempotency-Key must be 1 to 255 printable ASCII characters without spaces",
                   "Idempotency-Key");
  }
  return IdempotencyKey{key, sha256_hex({request.method, " ", request.path, "\n", media_type(request), "\n", request.body})};
}

long long integer_parameter(const httplib::Request& request, const std::string& name, long long fallback,
                            long long lowest, long long highest) {
  if (!request.has_param(name)) return fallback;
  const std::string text = request.get_param_value(name);
  long long value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size() || value < lowest || value > highest) {
    throw ApiError(ProblemKind::invalid_field,
                   name + " must be an integer from " + std::to_string(lowest) + " to " + std::to_string(highest) +
                       ", got '" + text + "'",
                   name);
  }
  return value;
}

PageRequest page_request(const httplib::Request& request, int default_size) {
  PageRequest page;
  // AIP-158: 0 means the default; sizes above the maximum are coerced down by the store.
  page.page_size = static_cast<int>(integer_parameter(request, "page_size", default_size, 0, 1'000'000));
  if (page.page_size == 0) page.page_size = default_size;
  page.page_token = request.get_param_value("page_token");
  return page;
}

long max_points_parameter(const httplib::Request& request, long fallback) {
  return static_cast<long>(integer_parameter(request, "max_points", fallback, 2, 1'000'000));
}

bool wants_csv(const httplib::Request& request) {
  if (request.has_param("format")) {
    const std::string format = request.get_param_value("format");
    if (format == "csv") return true;
    if (format == "json") return false;
    throw ApiError(ProblemKind::invalid_field, "format must be csv or json, got '" + format + "'", "format");
  }
  return request.get_header_value("Accept").find("text/csv") != std::string::npos;
}

std::string etag_of(const std::string& body) { return "\"" + sha256_hex({body}).substr(0, 32) + "\""; }

void require_utf8(std::string_view value, const char* field) {
  if (!is_valid_utf8(value)) {
    throw ApiError(ProblemKind::invalid_field,
                   std::string(field) + " is not valid UTF-8: send text as UTF-8 (percent-encode a query parameter's UTF-8 "
                                        "bytes)",
                   field);
  }
}

}  // namespace manipid::api::http
