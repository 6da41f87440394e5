#!/usr/bin/env bash
# Installs the Debian packages manipid needs to build and test that are missing: the [build]
# and [test] sections of scripts/debian-packages.txt, read by scripts/packages.sh (the parser
# docker/Dockerfile uses too). Idempotent and quiet when everything is already there. Needs
# root (or sudo) only when something is missing.
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
[[ ${#missing[@]} -eq 0 ]] && exit 0

echo "setup: installing ${missing[*]}" >&2
sudo=()
[[ $(id -u) -eq 0 ]] || sudo=(sudo)
export DEBIAN_FRONTEND=noninteractive
"${sudo[@]}" apt-get update -qq >/dev/null
"${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "setup: done" >&2
