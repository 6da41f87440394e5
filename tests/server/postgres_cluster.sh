#!/usr/bin/env bash
# postgres_cluster.sh — a private PostgreSQL cluster for the tests (the ctest fixture "postgres"):
#   postgres_cluster.sh start STATE_FILE   initdb into a new temporary directory, Unix socket only
#                                          (listen_addresses='', the socket in that directory),
#                                          start it, and write a libpq URI template to STATE_FILE
#                                          ("%s" where the database name goes) and the directory;
#                                          the role manipid_password signs in with the password
#                                          manipid-test-secret, every other role is trusted
#   postgres_cluster.sh stop STATE_FILE    stop it and remove the directory and STATE_FILE
# initdb refuses to run as root (CI runs as root): then the server binaries run as the `postgres`
# user the Debian package creates, and the directory is given to it. Without PostgreSQL's
# server binaries (Debian package postgresql), start says so, writes no STATE_FILE and exits 0:
# the tests that need the cluster then report themselves skipped.
# The cluster trades durability for speed (fsync off): it lives for one test run.
set -euo pipefail
action=${1:-}
state=${2:-}
[[ ( "$action" == start || "$action" == stop ) && -n "$state" ]] || {
  echo "usage: postgres_cluster.sh start|stop STATE_FILE" >&2
  exit 2
}

bindir=$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -1 || true)
as_owner() {
  if [[ $(id -u) -eq 0 ]]; then
    (cd / && runuser -u postgres -- "$@")
  else
    "$@"
  fi
}

if [[ "$action" == stop ]]; then
  [[ -f "$state" ]] || exit 0
  dir=$(sed -n 2p "$state")
  if [[ -n "$dir" && -d "$dir/data" ]]; then
    as_owner "$bindir/pg_ctl" -D "$dir/data" -m immediate -w stop >/dev/null 2>&1 || true
  fi
  [[ -n "$dir" && "$dir" == /tmp/manipid-pg.* ]] && rm -rf "$dir"
  rm -f "$state"
  exit 0
fi

rm -f "$state"
if [[ -z "$bindir" || ! -x "$bindir/initdb" ]]; then
  echo "postgres_cluster: PostgreSQL's server binaries are not installed (Debian package postgresql): the PostgreSQL tests skip"
  exit 0
fi
if [[ $(id -u) -eq 0 ]] && ! id postgres >/dev/null 2>&1; then
  echo "postgres_cluster: running as root without a 'postgres' user to run the server as: the PostgreSQL tests skip"
  exit 0
fi
dir=$(mktemp -d /tmp/manipid-pg.XXXXXX)
[[ $(id -u) -eq 0 ]] && chown postgres "$dir"
as_owner "$bindir/initdb" -D "$dir/data" -U postgres -A trust -E UTF8 --no-locale -N >"$dir/initdb.log" 2>&1 || {
  cat "$dir/initdb.log" >&2
  exit 1
}
# One role signs in with a password (scram-sha-256), so a wrong one can be tested; every other
# role is trusted on the socket. pg_hba.conf is read top down: this line first.
hba="$dir/data/pg_hba.conf"
as_owner bash -c "{ echo 'local all manipid_password scram-sha-256'; cat '$hba'; } >'$hba.new' && mv '$hba.new' '$hba'"
options="-c listen_addresses='' -c unix_socket_directories='$dir' -c fsync=off -c synchronous_commit=off"
options+=" -c full_page_writes=off -c max_connections=300"
as_owner "$bindir/pg_ctl" -D "$dir/data" -o "$options" -l "$dir/server.log" -w -t 60 start >/dev/null || {
  cat "$dir/server.log" >&2
  exit 1
}
as_owner "$bindir/psql" -h "$dir" -U postgres -d postgres -qc \
  "CREATE ROLE manipid_password LOGIN CREATEDB PASSWORD 'manipid-test-secret'" >/dev/null
printf 'postgresql:///%%s?host=%s&user=postgres\n%s\n' "$dir" "$dir" >"$state"
echo "postgres_cluster: PostgreSQL $("$bindir/postgres" --version | awk '{print $3}') on the socket in $dir"
