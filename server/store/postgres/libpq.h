// libpq.h — libpq's functions, loaded when the PostgreSQL store is first used.
//
// Linked normally, libpq brings ~20 libraries (Kerberos, LDAP, SASL, GnuTLS, …) that the
// dynamic loader maps and relocates at every start of every process: 4.3 ms on this machine
// (an empty program linked with and without -lpq), more than half of `manipid`'s start-up,
// paid by every CLI command and by a SQLite service that never opens PostgreSQL. Loaded with
// dlopen on the store's first connection instead, only the processes that use PostgreSQL pay,
// once. The declarations (types, constants) still come from libpq-fe.h; calling a function
// directly would fail to link, so every call goes through libpq().
#pragma once

#include <libpq-fe.h>

namespace manipid::server::store::postgres {

// The functions the store calls; the one list both the table and its loading are built from.
#define MANIPID_LIBPQ_FUNCTIONS(X)                                                                                \
  X(PQclear) X(PQcmdTuples) X(PQconnectdb) X(PQconsumeInput) X(PQerrorMessage) X(PQexec) X(PQexecParams)      \
  X(PQexecPrepared) X(PQfinish) X(PQfreemem) X(PQgetResult) X(PQgetisnull) X(PQgetlength) X(PQgetvalue)       \
  X(PQnotifies) X(PQntuples) X(PQprepare) X(PQputCopyData) X(PQputCopyEnd) X(PQresultErrorField)             \
  X(PQresultErrorMessage) X(PQresultStatus) X(PQsetNoticeProcessor) X(PQsocket) X(PQstatus)                  \
  X(PQtransactionStatus)

/// Pointers to libpq's functions, named as libpq names them.
struct Libpq {
#define MANIPID_LIBPQ_MEMBER(name) decltype(&::name) name = nullptr;
  MANIPID_LIBPQ_FUNCTIONS(MANIPID_LIBPQ_MEMBER)
#undef MANIPID_LIBPQ_MEMBER
};

/// libpq (libpq.so.5, Debian package libpq5), loaded on the first call and kept for the
/// process's life. Thread-safe. Throws StoreError saying what is missing when it cannot be
/// loaded; the next call tries again.
const Libpq& libpq();

}  // namespace manipid::server::store::postgres
