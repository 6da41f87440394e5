// request_helpers.h — internal to the routes: reading what a request says beyond its path —
// whom its bearer token stands for, media type, JSON body, Idempotency-Key and its fingerprint,
// integer and paging query parameters, ?format= / Accept: text/csv — and the ETag of an answer.
// Each throws ApiError naming the header or parameter at fault.
#pragma once

#include "manipid/api/records.h"

#include "http/route_state.h"  // includes httplib.h, after the manipid headers

#include <nlohmann/json.hpp>

#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>

namespace manipid::api::http {

/// SHA-256 of the parts one after the other, in hex: the digest of their concatenation, without
/// making it (an idempotent upload's body is not copied to be hashed).
std::string sha256_hex(std::initializer_list<std::string_view> parts);

/// Constant time in the strings' content: the comparison leaks nothing but their lengths (callers
/// compare SHA-256 digests, all of one length).
bool token_matches(const std::string& given, const std::string& expected);

/// Whom the request acts for, by its "Authorization: Bearer <token>": the admin with owner "" on a
/// server without tokens; nullopt when the server has tokens and the request carries none of them.
/// The token's digest is compared with every credential's, all of them every time.
std::optional<Caller> identify(const RouteState& state, const httplib::Request& request);
/// identify() in a handler (the pre-routing hook let the request through): 401 ApiError when it
/// finds no one (a route outside the token's reach, such as /metrics without any token).
Caller caller_of(const RouteState& state, const httplib::Request& request);

/// The Content-Type without parameters, spaces removed, lower case ("" when absent).
std::string media_type(const httplib::Request& request);

/// True when the body's first non-blank character opens a JSON object or array.
bool looks_like_json(const std::string& body);

/// Throws ApiError(invalid_field, `field`) when `value` (a query parameter, a document) is not UTF-8: it
/// would be stored and answered as JSON, which cannot hold it.
void require_utf8(std::string_view value, const char* field);

/// The body's text, when its media type is JSON's (as json_body accepts) and it is not empty.
const std::string& json_text(const httplib::Request& request);
/// The body as a JSON object. Accepts application/json, and — because `curl -d @file` sends
/// application/x-www-form-urlencoded unless told otherwise — an unlabelled body that is JSON.
nlohmann::json json_body(const httplib::Request& request);

/// The Idempotency-Key header (printable ASCII, 1..255 characters) with the fingerprint of
/// the request it came with: the same key with a different body is refused (422).
std::optional<IdempotencyKey> idempotency_key(const httplib::Request& request);

/// ?name= as an integer in [lowest, highest]; `fallback` when absent.
long long integer_parameter(const httplib::Request& request, const std::string& name, long long fallback,
                            long long lowest, long long highest);

/// ?page_size= and ?page_token= (AIP-158).
PageRequest page_request(const httplib::Request& request, int default_size);

/// ?max_points= for the drawing endpoints: at most this many points (about), 2 to 1,000,000.
long max_points_parameter(const httplib::Request& request, long fallback);

/// ?format=csv|json decides; without it, an Accept header naming text/csv.
bool wants_csv(const httplib::Request& request);

/// A strong ETag (quoted) of an answer's body.
std::string etag_of(const std::string& body);

}  // namespace manipid::api::http
