// token_file.cpp — reading and checking `manipid serve --token-file` (token_file.h).
#include "cli/token_file.h"

#include "cli/common.h"

#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <map>
#include <sstream>

namespace manipid::server::cli {
namespace {

bool is_name(const std::string& text) {
  return !text.empty() && text.size() <= 64 && std::all_of(text.begin(), text.end(), [](unsigned char c) {
    return std::isalnum(c) != 0 || c == '.' || c == '_' || c == '-';
  });
}

bool is_token(const std::string& text) {
  return !text.empty() && std::all_of(text.begin(), text.end(), [](unsigned char c) {
    return std::isalnum(c) != 0 || c == '-' || c == '.' || c == '_' || c == '~' || c == '+' || c == '/' || c == '=';
  });
}

/// The file holds every group's secret: refused, as ssh refuses a private key, when users outside
/// its owner and group may read it, or anyone but its owner may write it (and add a token of theirs).
void check_permissions(const std::string& path) {
  struct stat info {};
  if (::stat(path.c_str(), &info) != 0) {
    throw UsageError("--token-file " + path + ": " + std::strerror(errno));
  }
  if (!S_ISREG(info.st_mode)) throw UsageError("--token-file " + path + ": not a regular file");
  if ((info.st_mode & (S_IROTH | S_IWOTH | S_IWGRP)) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof mode, "%03o", static_cast<unsigned>(info.st_mode & 0777));
    throw UsageError("--token-file " + path + ": mode " + mode +
                     " lets other users read it or change it, and it holds every group's token: chmod 600 " + path +
                     " (or 640)");
  }
}

}  // namespace

std::vector<api::NamedToken> read_token_file(const std::string& path) {
  check_permissions(path);
  const std::string text = read_text(path);
  std::vector<api::NamedToken> tokens;
  std::map<std::string, int> name_lines;   // name → the line that gave it
  std::map<std::string, int> token_lines;  // token → the line that gave it
  std::istringstream lines(text);
  int number = 0;
  for (std::string line; std::getline(lines, line);) {
    ++number;
    const std::string where = "--token-file " + path + " line " + std::to_string(number) + ": ";
    if (!line.empty() && line.back() == '\r') line.pop_back();  // a file written on Windows
    const std::size_t first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') continue;
    std::vector<std::string> fields;
    std::istringstream words(line);
    for (std::string word; words >> word;) fields.push_back(word);
    api::NamedToken named;
    // "admin" is the mark, never a name: "admin TOKEN" would otherwise read two ways.
    if (!fields.empty() && fields[0] == "admin") {
      named.admin = true;
      fields.erase(fields.begin());
    }
    // NAME:TOKEN is one field; a token never holds ':' (nor a name), so the first ':' splits it.
    if (fields.size() == 1 && fields[0].find(':') != std::string::npos) {
      const std::size_t colon = fields[0].find(':');
      fields = {fields[0].substr(0, colon), fields[0].substr(colon + 1)};
    }
    if (fields.size() != 2) {
      throw UsageError(where + "expected NAME TOKEN, NAME:TOKEN or admin NAME TOKEN (" + std::to_string(fields.size()) +
                       " fields found; '#' starts a comment)");
    }
    named.name = fields[0];
    named.token = fields[1];
    if (!is_name(named.name)) {
      throw UsageError(where + "a name is 1 to 64 of the letters A-Z a-z, digits and . _ -");
    }
    if (named.name == "admin") {
      throw UsageError(where + "admin marks an admin token (admin NAME TOKEN); it is not a name");
    }
    // The token is never echoed: the message says what is wrong with it, not what it is.
    if (!is_token(named.token)) {
      throw UsageError(where + "the token of " + named.name + " may hold only A-Z a-z 0-9 - . _ ~ + / =");
    }
    if (named.token.size() < min_token_length) {
      throw UsageError(where + "the token of " + named.name + " is " + std::to_string(named.token.size()) +
                       " characters; at least " + std::to_string(min_token_length) +
                       " (e.g. openssl rand -hex 24)");
    }
    if (const auto earlier = name_lines.find(named.name); earlier != name_lines.end()) {
      throw UsageError(where + "the name " + named.name + " is given twice (line " + std::to_string(earlier->second) +
                       " too): each owner has one token");
    }
    if (const auto earlier = token_lines.find(named.token); earlier != token_lines.end()) {
      throw UsageError(where + "the token of " + named.name + " is also line " + std::to_string(earlier->second) +
                       "'s: a token stands for one name");
    }
    name_lines[named.name] = number;
    token_lines[named.token] = number;
    tokens.push_back(std::move(named));
  }
  if (tokens.empty()) throw UsageError("--token-file " + path + ": no tokens in it (one NAME TOKEN a line)");
  return tokens;
}

}  // namespace manipid::server::cli
