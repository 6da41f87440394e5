// token_file.h — `manipid serve --token-file`: the named bearer tokens a lab server shared by
// groups takes, read and checked once at start-up (the format is read_token_file's comment).
#pragma once

#include "manipid/api/routes.h"

#include <string>
#include <vector>

namespace manipid::server::cli {

/// The shortest token taken: 16 characters (a guessable token would make the names meaningless).
inline constexpr std::size_t min_token_length = 16;

/// Reads a token file: one token a line,
///
///     # comments and blank lines are skipped
///     alice  9f8e7d6c5b4a39281706f5e4   (NAME TOKEN: alice's datasets, robots and jobs)
///     bob:Zm9vYmFyYmF6cXV4cXV1eA        (NAME:TOKEN, the same)
///     admin carol 0a1b2c3d4e5f60718293  (admin NAME TOKEN: carol sees and acts on everyone's)
///
/// A NAME is 1 to 64 of A-Z a-z 0-9 . _ - other than "admin" (it is shown in logs and as resources'
/// "owner"); a TOKEN at least 16 of A-Z a-z 0-9 - . _ ~ + / = (RFC 6750's token characters). Throws
/// UsageError, naming the file and the line (never a token), for: a file other users may read or
/// anyone but its owner may write (chmod 600 or 640), a line that is none of the three forms, a bad
/// name or token, a token shorter than 16, a name or a token given twice, a file with no token.
std::vector<api::NamedToken> read_token_file(const std::string& path);

}  // namespace manipid::server::cli
