#!/usr/bin/env bash
# Installs the Debian packages manipid needs to build and test that are missing: the [build]
# and [test] sections of scripts/debian-packages.txt, read by scripts/packages.sh (the parser
# docker/Dockerfile uses too), and [web] (Node.js, npm) when no npm is on PATH. Then, for a
# build, fetches the dashboard's chart library and browser-test driver as web/package-lock.json
# pins them (`npm ci` in web/, only when the lock file changed). Idempotent and quiet when
# everything is already there. Needs root (or sudo) only when a package is missing.
#
#   bash scripts/setup.sh                 # build and test packages
#   bash scripts/setup.sh build           # other sections, e.g. only what the build needs
#   bash scripts/setup.sh --list [SECTION...]   # print the packages it would check, install nothing
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
list_only=false
if [[ "${1:-}" == --list ]]; then
  list_only=true
  shift
fi
sections=("$@")
[[ ${#sections[@]} -gt 0 ]] || sections=(build test)
wants_build=false
[[ " ${sections[*]} " == *" build "* ]] && wants_build=true
# The dashboard's build needs npm; a machine with its own Node.js keeps it.
if $wants_build && ! command -v npm >/dev/null; then sections+=(web); fi
wanted_text=$(bash "$here/packages.sh" "${sections[@]}")
mapfile -t wanted <<<"$wanted_text"
if $list_only; then
  printf '%s\n' "${wanted[@]}"
  exit 0
fi

missing=()
for package in "${wanted[@]}"; do
  status=$(dpkg-query -W -f='${Status}' "$package" 2>/dev/null || true)
  [[ "$status" == "install ok installed" ]] || missing+=("$package")
done
if [[ ${#missing[@]} -gt 0 ]]; then
  echo "setup: installing ${missing[*]}" >&2
  sudo=()
  [[ $(id -u) -eq 0 ]] || sudo=(sudo)
  export DEBIAN_FRONTEND=noninteractive
  "${sudo[@]}" apt-get update -qq >/dev/null
  "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  echo "setup: done" >&2
fi

# The dashboard's npm packages (uPlot; playwright-core for its browser test), as locked.
web="$here/../web"
if $wants_build && { [[ ! -f "$web/node_modules/.package-lock.json" ]] ||
                     [[ "$web/package-lock.json" -nt "$web/node_modules/.package-lock.json" ]]; }; then
  echo "setup: npm ci in web/" >&2
  if ! (cd "$web" && npm ci --no-audit --no-fund --loglevel=error >/dev/null); then
    echo "setup: warning: npm ci failed (no route to the npm registry?): manipid builds without its dashboard" >&2
  fi
fi
