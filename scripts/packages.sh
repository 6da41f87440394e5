#!/usr/bin/env bash
# packages.sh — prints the Debian package names of the given sections of
# scripts/debian-packages.txt, one a line, in file order, each name once. The one parser of
# that file: scripts/setup.sh and docker/Dockerfile both call it, so they cannot read the list
# differently. Needs only bash (it runs in a bare debian:bookworm-slim).
#
#   scripts/packages.sh build test        # what setup.sh installs
#   scripts/packages.sh runtime           # what the image's runtime stage installs
#   scripts/packages.sh --sections        # the section names in the file
#   scripts/packages.sh --file FILE ...   # another list (tests)
#
# Fails (exit 2) on an unknown section, an empty one, a malformed line, a package name Debian
# would not accept or a name listed twice in one section: a typo stops the build instead of
# quietly installing less.
set -euo pipefail

list="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/debian-packages.txt"
want_sections=false
if [[ "${1:-}" == --file ]]; then
  [[ $# -ge 2 ]] || { echo "packages.sh: --file needs a file name" >&2; exit 2; }
  list=$2
  shift 2
fi
if [[ "${1:-}" == --sections ]]; then
  want_sections=true
  shift
fi
if ! $want_sections && [[ $# -eq 0 ]]; then
  echo "usage: packages.sh [--file FILE] SECTION... | --sections   (sections: build, test, web, runtime, proxy)" >&2
  exit 2
fi
[[ -r "$list" ]] || { echo "packages.sh: cannot read $list" >&2; exit 2; }

declare -A requested=() seen=() found=() count=() listed=()
for section in "$@"; do requested[$section]=1; done

section=""
number=0
names=()
sections=()
while IFS= read -r line || [[ -n "$line" ]]; do
  number=$((number + 1))
  line=${line%%#*}                                  # comment
  line=${line#"${line%%[![:space:]]*}"}              # leading blanks
  line=${line%"${line##*[![:space:]]}"}              # trailing blanks
  [[ -n "$line" ]] || continue
  if [[ "$line" =~ ^\[([a-z0-9_-]+)\]$ ]]; then
    section=${BASH_REMATCH[1]}
    [[ -z "${found[$section]:-}" ]] || { echo "packages.sh: $list:$number: section [$section] appears twice" >&2; exit 2; }
    found[$section]=1
    count[$section]=0
    sections+=("$section")
    continue
  fi
  if [[ -z "$section" ]]; then
    echo "packages.sh: $list:$number: '$line' comes before any [section]" >&2
    exit 2
  fi
  # Debian policy 5.6.1: lower case letters, digits, + - . ; at least two characters, starting alphanumeric.
  if ! [[ "$line" =~ ^[a-z0-9][a-z0-9+.-]+$ ]]; then
    echo "packages.sh: $list:$number: '$line' is not a Debian package name" >&2
    exit 2
  fi
  [[ -z "${listed[$section/$line]:-}" ]] || { echo "packages.sh: $list:$number: $line is already in [$section]" >&2; exit 2; }
  listed[$section/$line]=1
  count[$section]=$((count[$section] + 1))
  if [[ -n "${requested[$section]:-}" && -z "${seen[$line]:-}" ]]; then
    seen[$line]=1
    names+=("$line")
  fi
done <"$list"

if $want_sections; then
  printf '%s\n' "${sections[@]}"
  exit 0
fi
for section in "$@"; do
  [[ -n "${found[$section]:-}" ]] || { echo "packages.sh: no section [$section] in $list (sections: ${sections[*]})" >&2; exit 2; }
  [[ ${count[$section]} -gt 0 ]] || { echo "packages.sh: section [$section] of $list is empty" >&2; exit 2; }
done
printf '%s\n' "${names[@]}"
