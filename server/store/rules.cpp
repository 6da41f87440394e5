// rules.cpp — ids, time stamps, page sizes and page tokens shared by every store (rules.h).
#include "store/rules.h"

#include "store/encoding.h"

#include <chrono>
#include <cstdio>
#include <ctime>
#include <random>

namespace manipid::server::store {

namespace {

// FNV-1a, 32 bits: enough to catch edited tokens; the token is not a security boundary.
std::uint32_t fnv1a(std::string_view text, std::uint32_t hash = 2166136261u) {
  for (unsigned char character : text) {
    hash ^= character;
    hash *= 16777619u;
  }
  return hash;
}

std::string hex(std::uint64_t value, int width) {
  char buffer[17];
  std::snprintf(buffer, sizeof buffer, "%0*llx", width, static_cast<unsigned long long>(value));
  return buffer;
}

std::uint32_t token_check(std::string_view tag, std::string_view position, std::string_view context) {
  std::uint32_t hash = fnv1a(tag);
  hash = fnv1a(".", hash);
  hash = fnv1a(position, hash);
  hash = fnv1a("|", hash);
  return fnv1a(context, hash);
}

[[noreturn]] void malformed_token() {
  throw PageRequestError("page_token", "page_token is not a token this list returned (or the filter changed since)");
}

}  // namespace

std::string now_rfc3339() { return rfc3339_ago(std::chrono::seconds(0)); }

std::string rfc3339_ago(std::chrono::seconds age) {
  const auto now = std::chrono::system_clock::now() - age;
  const auto milliseconds =
      std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() % 1000;
  const std::time_t seconds = std::chrono::system_clock::to_time_t(now);
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char buffer[96];  // room for any int the fields could hold, so the compiler sees no truncation
  std::snprintf(buffer, sizeof buffer, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", utc.tm_year + 1900, utc.tm_mon + 1,
                utc.tm_mday, utc.tm_hour, utc.tm_min, utc.tm_sec, static_cast<int>(milliseconds));
  return buffer;
}

std::string random_id(std::string_view prefix) {
  thread_local std::mt19937_64 generator = [] {
    std::random_device device;
    std::seed_seq seed{device(), device(), device(), device(), device(), device(), device(), device()};
    return std::mt19937_64(seed);
  }();
  return std::string(prefix) + hex(generator(), 16);
}

std::string encode_page_token(std::string_view tag, std::int64_t position, std::string_view context) {
  const std::string digits = hex(static_cast<std::uint64_t>(position), 1);
  return std::string(tag) + "." + digits + "." + hex(token_check(tag, digits, context), 8);
}

std::int64_t decode_page_token(std::string_view token, std::string_view tag, std::string_view context) {
  if (token.size() <= tag.size() + 1 || token.substr(0, tag.size()) != tag || token[tag.size()] != '.') {
    malformed_token();
  }
  const std::string_view rest = token.substr(tag.size() + 1);
  const auto dot = rest.find('.');
  if (dot == std::string_view::npos || dot == 0 || dot > 16) malformed_token();
  const std::string_view digits = rest.substr(0, dot);
  const std::string_view check = rest.substr(dot + 1);
  std::uint64_t position = 0;
  for (char digit : digits) {
    if (digit >= '0' && digit <= '9') {
      position = position * 16 + static_cast<std::uint64_t>(digit - '0');
    } else if (digit >= 'a' && digit <= 'f') {
      position = position * 16 + static_cast<std::uint64_t>(digit - 'a' + 10);
    } else {
      malformed_token();
    }
  }
  // Re-encoding must give the same text: rejects leading zeros, upper case and a wrong check.
  if (hex(position, 1) != digits || check != hex(token_check(tag, digits, context), 8)) malformed_token();
  return static_cast<std::int64_t>(position);
}

std::string list_context(const api::OwnerScope& scope) {
  // Every owner's lists keep the context they had before owners existed (their tokens stay good).
  return scope ? "owner=" + *scope + ";" : "";
}

std::string job_list_context(const api::OwnerScope& scope, const api::JobFilter& filter) {
  return list_context(scope) + "state=" + (filter.state ? state_text(*filter.state) : "") +
         ";kind=" + (filter.kind ? kind_text(*filter.kind) : "") + ";robot=" + filter.robot_id;
}

int effective_page_size(int requested) {
  if (requested < 0) throw PageRequestError("page_size", "page_size must not be negative");
  if (requested == 0) return 50;
  return requested > 1000 ? 1000 : requested;
}

}  // namespace manipid::server::store
