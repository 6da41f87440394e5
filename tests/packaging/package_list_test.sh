#!/usr/bin/env bash
# package_list_test.sh — checks that scripts/setup.sh and docker/Dockerfile install from the one
# Debian package list (scripts/debian-packages.txt) through the one parser (scripts/packages.sh),
# so they cannot drift, and that the image's [runtime] section covers every shared library the
# manipid executable links against. Needs no Docker daemon.
#
#   tests/packaging/package_list_test.sh [path/to/manipid]
#
# Without the binary the ldd check is skipped. A debug (sanitizer) build works too: the
# sanitizer runtimes are not expected in [runtime]. Exit 0 when every check passes.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
packages="$root/scripts/packages.sh"
dockerfile="$root/docker/Dockerfile"
setup="$root/scripts/setup.sh"
binary=${1:-}

failures=0
pass() { printf 'ok    %s\n' "$1"; }
fail() { printf 'FAIL  %s\n' "$1"; [[ -z "${2:-}" ]] || printf '      %s\n' "$2"; failures=$((failures + 1)); }
work=$(mktemp -d "${TMPDIR:-/tmp}/manipid-packaging-test.XXXXXX")
trap 'rm -rf -- "$work"' EXIT

# ---- The list parses, with the three sections, none empty --------------------------------
if sections=$(bash "$packages" --sections 2>"$work/err"); then
  for section in build test web runtime proxy; do
    if grep -qx "$section" <<<"$sections"; then pass "section [$section] exists"; else fail "section [$section] exists"; fi
    if names=$(bash "$packages" "$section" 2>"$work/err") && [[ -n "$names" ]]; then
      pass "section [$section] parses, $(wc -l <<<"$names") packages"
    else
      fail "section [$section] parses and is non-empty" "$(cat "$work/err")"
    fi
  done
else
  fail "scripts/packages.sh --sections" "$(cat "$work/err")"
fi
build=$(bash "$packages" build 2>/dev/null || true)
runtime=$(bash "$packages" runtime 2>/dev/null || true)

# The parser refuses what would silently install less.
bad() {  # bad DESCRIPTION CONTENT SECTION...: packages.sh must fail on this list
  local what=$1 content=$2
  shift 2
  printf '%s\n' "$content" >"$work/bad.txt"
  if bash "$packages" --file "$work/bad.txt" "$@" >/dev/null 2>&1; then fail "parser refuses $what"; else pass "parser refuses $what"; fi
}
bad "an unknown section" $'[build]\ncmake' runtime
bad "an empty section" $'[build]\n[runtime]\nlibc6' build
bad "a name before any section" $'cmake\n[build]\nmake' build
bad "an invalid name" $'[build]\nlib_Foo' build
bad "two names on one line" $'[build]\ncmake make' build
bad "a name twice in a section" $'[build]\ncmake\ncmake' build
printf '# comment\n\n[build]   # why\n  cmake   # tool\nmake\n[test]\ncmake\njq\n' >"$work/good.txt"
got=$(bash "$packages" --file "$work/good.txt" build test | tr '\n' ' ')
if [[ "$got" == "cmake make jq " ]]; then pass "parser: comments, blanks, order, each name once"; else fail "parser: comments, blanks, order, each name once" "got '$got'"; fi

# ---- setup.sh installs [build] and [test] through packages.sh -----------------------------
expected=$(bash "$packages" build test)
if listed=$(bash "$setup" --list 2>&1) && [[ "$listed" == "$expected" ]]; then
  pass "setup.sh --list is exactly packages.sh build test"
else
  fail "setup.sh --list is exactly packages.sh build test" "$(diff <(echo "$expected") <(echo "$listed") | head -5 | tr '\n' ' ')"
fi
if grep -q 'packages\.sh' "$setup" && ! grep -v '^[[:space:]]*#' "$setup" | grep -q 'debian-packages\.txt'; then
  pass "setup.sh reads the list only through packages.sh"
else
  fail "setup.sh reads the list only through packages.sh"
fi

# ---- Dockerfile: packages only from the list, through packages.sh -------------------------
# Instructions with their continuation lines joined, comments dropped.
instructions=$(sed -e '/^[[:space:]]*#/d' "$dockerfile" | sed -e ':a' -e '/\\$/{N;s/\\\n/ /;ba' -e '}')
# Stages: "name<TAB>instruction" for every instruction after a FROM ... AS name.
staged=$(awk 'BEGIN{IGNORECASE=1} /^FROM[[:space:]]/{stage=""; for(i=1;i<=NF;i++) if(toupper($i)=="AS") stage=$(i+1)} stage!=""{print stage "\t" $0}' <<<"$instructions")
stage_has() { grep -P "^$1\t" <<<"$staged" | cut -f2- | grep -qE -- "$2"; }

for pair in build:build runtime:runtime; do
  stage=${pair%%:*} section=${pair#*:}
  if stage_has "$stage" '^COPY .*scripts/packages\.sh' && stage_has "$stage" '^COPY .*scripts/debian-packages\.txt'; then
    pass "stage $stage copies packages.sh and debian-packages.txt"
  else
    fail "stage $stage copies packages.sh and debian-packages.txt"
  fi
  if stage_has "$stage" "^RUN .*packages=\\\$\\([^)]*packages\\.sh[^)]* $section[ )]"; then
    pass "stage $stage takes section [$section] from packages.sh"
  else
    fail "stage $stage takes section [$section] from packages.sh"
  fi
  # shellcheck disable=SC2016 # a literal $packages
  if stage_has "$stage" 'apt-get install .*\$packages'; then
    pass "stage $stage installs \$packages"
  else
    fail "stage $stage installs \$packages"
  fi
done
# Every apt-get install names no package itself: after "install", only options and $variables.
literal=$(grep -oE 'apt-get install[^;&|]*' <<<"$instructions" | sed 's/apt-get install//' | tr ' ' '\n' |
          grep -vE '^$|^-|^"?\$\{?[A-Za-z_]+\}?"?$' || true)
if [[ -z "$literal" ]]; then
  pass "Dockerfile hard-codes no package name in apt-get install"
else
  fail "Dockerfile hard-codes no package name in apt-get install" "found: $(tr '\n' ' ' <<<"$literal")"
fi
# shellcheck disable=SC2016 # a literal $packages
if grep -qE 'apt(-get)? +(install|-y)' <<<"$(grep -vE 'apt-get install[^;&|]*\$packages' <<<"$instructions")"; then
  fail "every apt-get install in the Dockerfile installs \$packages"
else
  pass "every apt-get install in the Dockerfile installs \$packages"
fi
# Nothing but packages.sh reads the list: no RUN feeds it to sed, awk, grep, cat, xargs, read...
if grep -E '^RUN ' <<<"$instructions" | grep -qE '(sed|awk|grep|cat|xargs|read|<)[^;&|]*debian-packages\.txt'; then
  fail "Dockerfile reads debian-packages.txt only through packages.sh"
else
  pass "Dockerfile reads debian-packages.txt only through packages.sh"
fi

# The runtime image's other promises.
check_line() {  # check_line DESCRIPTION REGEX
  if grep -qE -- "$2" <<<"$instructions"; then pass "$1"; else fail "$1"; fi
}
check_line "ARG BASE defaults to debian:bookworm(-slim)" '^ARG BASE=debian:bookworm(-slim)?$'
check_line "both stages FROM \${BASE}" '^FROM \$\{BASE\} AS build'
check_line "runtime stage FROM \${BASE}" '^FROM \$\{BASE\} AS runtime'
check_line "builds only the manipid target of the release preset" 'cmake --build --preset release --target manipid'
check_line "non-root USER" '^USER manipid'
check_line "EXPOSE 8080" '^EXPOSE 8080$'
check_line "VOLUME /data" '^VOLUME \["/data"\]'
check_line "STOPSIGNAL SIGTERM" '^STOPSIGNAL SIGTERM$'
check_line "HEALTHCHECK on /healthz" '^HEALTHCHECK .*/healthz'
check_line "ENTRYPOINT serve on 0.0.0.0 with /data/manipid.db" \
  '^ENTRYPOINT \["manipid", "serve", "--host", "0.0.0.0", "--db", "/data/manipid.db"\]$'
# The HEALTHCHECK's program must be in the image: curl from [runtime].
if grep -qx curl <<<"$runtime"; then pass "curl (HEALTHCHECK) is in [runtime]"; else fail "curl (HEALTHCHECK) is in [runtime]"; fi

# ---- compose.yaml -------------------------------------------------------------------------
compose="$root/docker/compose.yaml"
if command -v python3 >/dev/null && python3 -c 'import yaml' 2>/dev/null; then
  if python3 - "$compose" <<'EOF'
import sys, yaml
doc = yaml.safe_load(open(sys.argv[1]))
service = doc["services"]["manipid"]
assert service["init"] is True, "init: true"
assert service["build"]["dockerfile"] == "docker/Dockerfile", service["build"]
assert any(str(v).endswith(":/data") and str(v).split(":")[0] in doc["volumes"] for v in service["volumes"]), "named volume on /data"
assert any(str(p).endswith(":8080") for p in service["ports"]), "port 8080"
assert "MANIPID_TOKEN" in service["environment"], "token from the environment"
# Profile "postgres": an API process without job threads and scalable workers on one database.
api, worker, postgres = (doc["services"][name] for name in ("api", "worker", "postgres"))
assert all(s["profiles"] == ["postgres"] for s in (api, worker, postgres)), "profile postgres"
assert api["entrypoint"][:2] == ["manipid", "serve"] and "--workers" in api["entrypoint"], api["entrypoint"]
assert api["entrypoint"][api["entrypoint"].index("--workers") + 1] == "0", "the API runs no job"
assert worker["entrypoint"][:2] == ["manipid", "worker"], worker["entrypoint"]
db = api["entrypoint"][api["entrypoint"].index("--db") + 1]
assert db.startswith("postgresql://") and db == worker["entrypoint"][worker["entrypoint"].index("--db") + 1], db
assert ":" not in db.split("//")[1].split("@")[0], "no password in the URI"
assert "PGPASSWORD" in api["environment"] and "PGPASSWORD" in worker["environment"], "password from the environment"
assert worker["healthcheck"]["disable"] is True, "a worker serves no /healthz"
assert "ports" not in worker, "workers publish no port (they scale)"
EOF
  then pass "compose.yaml: init, named volume on /data, port 8080, MANIPID_TOKEN; profile postgres: API + workers"
  else fail "compose.yaml: init, named volume on /data, port 8080, MANIPID_TOKEN; profile postgres: API + workers"
  fi
else
  echo "skip  compose.yaml (no python3-yaml)"
fi

# ---- .dockerignore keeps build trees out of the context ------------------------------------
if grep -qxE '/?build/?|\*\*/build/?' "$root/.dockerignore"; then pass ".dockerignore excludes build/"; else fail ".dockerignore excludes build/"; fi
for needed in CMakeLists.txt CMakePresets.json core api server scripts; do
  if grep -qxE "/?$needed/?" "$root/.dockerignore"; then fail ".dockerignore keeps $needed (the build stage copies it)"; fi
done

# ---- Every package named exists in Debian (installed here, or known to apt) ----------------
unknown=()
while IFS= read -r package; do
  [[ -n "$package" ]] || continue
  status=$(dpkg-query -W -f='${Status}' "$package" 2>/dev/null || true)
  [[ "$status" == "install ok installed" ]] && continue
  apt-cache show "$package" >/dev/null 2>&1 || unknown+=("$package")
done < <(bash "$packages" build test runtime)
if [[ ${#unknown[@]} -eq 0 ]]; then pass "every listed package is installed or known to apt"; else fail "every listed package is installed or known to apt" "unknown: ${unknown[*]}"; fi

# ---- [runtime] covers what the binary and its HTTP module link against ----------------------
# The module manipid-http.so is built beside the binary; `manipid serve` loads it, and the image
# must hold it where serve looks (../lib/manipid/ from the executable).
check_line "the image holds manipid-http.so in /usr/local/lib/manipid/ (../lib/manipid from the binary)" \
  '^COPY --from=build /src/build/release/server/manipid-http\.so /usr/local/lib/manipid/manipid-http\.so$'
covered() {  # covered FILE: every library FILE links against is in [runtime] (or comes with a package there)
  local file=$1 library real owner package entry closure missing_libs
  local -a uncovered=() still=()
  missing_libs=$(ldd "$file" | grep 'not found' || true)
  [[ -z "$missing_libs" ]] || fail "ldd resolves every library of $(basename "$file")" "$missing_libs"
  # Libraries ldd resolves → their Debian packages (dpkg -S on the resolved path, /usr-merged).
  while IFS= read -r library; do
    [[ -n "$library" ]] || continue
    real=$(readlink -f -- "$library")
    owner=$(dpkg -S "$real" 2>/dev/null || dpkg -S "${real/#\/usr\/lib\//\/lib\/}" 2>/dev/null ||
            dpkg -S "$library" 2>/dev/null || true)
    package=${owner%%:*}
    if [[ -z "$package" ]]; then
      uncovered+=("$library(no package)")
      continue
    fi
    # Sanitizer runtimes come with the debug build only.
    [[ "$package" =~ ^lib(asan|ubsan|lsan|tsan)[0-9]+$ ]] && continue
    grep -qx -- "$package" <<<"$runtime" || uncovered+=("$package($library)")
  done < <(ldd "$file" | awk '$2 == "=>" && $3 ~ /^\// {print $3}')
  # A library a [runtime] package depends on (libpq5 → Kerberos, LDAP, GnuTLS, …) comes with it.
  if [[ ${#uncovered[@]} -gt 0 ]]; then
    # shellcheck disable=SC2086  # one name per word
    closure=$(apt-cache depends --recurse --no-recommends --no-suggests --no-conflicts --no-breaks --no-replaces \
                --no-enhances $runtime 2>/dev/null | grep -v '^ ' | sed 's/:any$//' | sort -u || true)
    for entry in "${uncovered[@]}"; do
      grep -qx -- "${entry%%(*}" <<<"$closure" || still+=("$entry")
    done
    uncovered=("${still[@]}")
  fi
  if [[ ${#uncovered[@]} -eq 0 ]]; then
    pass "[runtime] covers every library $(basename "$file") links against (or a [runtime] package depends on it)"
  else
    fail "[runtime] covers every library $(basename "$file") links against" "missing: ${uncovered[*]}"
  fi
}
if [[ -n "$binary" ]]; then
  module="$(dirname -- "$binary")/manipid-http.so"
  if [[ ! -x "$binary" ]]; then
    fail "binary $binary is executable"
  elif [[ ! -f "$module" ]]; then
    fail "the HTTP module is built beside the binary" "no $module"
  else
    covered "$binary"
    covered "$module"
    # What the module takes from the executable, the executable exports (else serve fails to load it).
    needed=$(nm -D --undefined-only "$module" | awk '{print $2}' | grep -E '^_ZN?K?7manipid|^_ZT[VIS]N7manipid' | sort -u || true)
    exported=$(nm -D --defined-only "$binary" | awk '{print $3}' | sort -u)
    absent=$(comm -23 <(echo "$needed") <(echo "$exported") | head -5)
    if [[ -n "$needed" && -z "$absent" ]]; then
      pass "$(basename "$binary") exports the $(wc -l <<<"$needed") manipid symbols manipid-http.so takes from it"
    else
      fail "$(basename "$binary") exports the manipid symbols manipid-http.so takes from it" "absent: ${absent:-none needed?}"
    fi
    # The one-shot commands do not load cpp-httplib: only the module links it.
    if ldd "$binary" | grep -q 'libcpp-httplib'; then
      fail "$(basename "$binary") does not link cpp-httplib (only manipid-http.so does)"
    else
      pass "$(basename "$binary") does not link cpp-httplib (only manipid-http.so does)"
    fi
  fi
else
  echo "skip  ldd coverage (no binary given)"
fi
# Loaded with dlopen on first use, so ldd does not list them: libpq when PostgreSQL is first
# used (server/store/postgres/libpq.h), FFTW when a long filter is (core/src/signal/fftw.h).
for loaded in "libpq5 libpq.so.5" "libfftw3-double3 libfftw3.so.3"; do
  read -r package library <<<"$loaded"
  if grep -qx "$package" <<<"$runtime"; then
    pass "[runtime] has $package ($library, loaded at run time)"
  else
    fail "[runtime] has $package ($library, loaded at run time)"
  fi
done

# Without a binary, a hint instead: the shared-library packages the [build] -dev packages pull
# (libsqlite3-dev → libsqlite3-0) that [runtime] lacks. Not all are linked, so not a failure.
[[ -n "$binary" ]] || while IFS= read -r dev; do
  [[ -n "$dev" ]] || continue
  depends=$(dpkg-query -W -f='${Depends}' "$dev" 2>/dev/null || apt-cache show --no-all-versions "$dev" 2>/dev/null | sed -n 's/^Depends: //p')
  for dependency in $(tr ',|' '\n' <<<"$depends" | sed -e 's/(.*)//' -e 's/:any//' -e 's/[[:space:]]//g'); do
    # A versioned shared-library package name: lib<name><soversion> (libnlopt0, libssl3, libcpp-httplib0.11, ...)
    [[ "$dependency" =~ ^lib[a-z0-9+.-]*[0-9]$ && "$dependency" != *-dev ]] || continue
    if ! grep -qx -- "$dependency" <<<"$runtime"; then
      echo "note  $dev depends on $dependency, not in [runtime] (fine if manipid does not link it)"
    fi
  done
done < <(grep -E -- '-dev$' <<<"$build")

if [[ $failures -gt 0 ]]; then
  echo "package_list_test: $failures check(s) failed" >&2
  exit 1
fi
echo "package_list_test: all checks passed"
