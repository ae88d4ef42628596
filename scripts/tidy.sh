#!/usr/bin/env bash
# Runs clang-tidy (the checks of .clang-tidy, clang-tidy 14) over the .cpp files of the given
# folders and prints each finding in the project's own files, then a count per check.
#
#   scripts/tidy.sh [-p BUILD] [-j JOBS] [FOLDER...]
#
# BUILD: a configured build folder (its compile_commands.json; default: build). FOLDER: source
# folders (default: batch collision common remesh scenegen simulation validation). About 20 s
# of CPU per file: not part of the test suite. Exit 0 without findings, 1 with, 2 on bad usage.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="$root/build"
jobs="$(nproc)"
while [ $# -gt 0 ]; do
  case "$1" in
    -p) build="${2:?tidy: -p needs a build folder}"; shift 2 ;;
    -j) jobs="${2:?tidy: -j needs a number}"; shift 2 ;;
    -j?*) jobs="${1#-j}"; shift ;;
    -h | --help) sed -n '2,10p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; exit 0 ;;
    -*) echo "tidy: unknown option '$1' (see --help)" >&2; exit 2 ;;
    *) break ;;
  esac
done
[[ "$jobs" =~ ^[1-9][0-9]*$ ]] || { echo "tidy: -j '$jobs' is not a positive number" >&2; exit 2; }
folders=("$@")
[ ${#folders[@]} -gt 0 ] || folders=(batch collision common remesh scenegen simulation validation)
program="$(command -v clang-tidy-14 || command -v clang-tidy || true)"
[ -n "$program" ] || { echo "tidy: clang-tidy not found (Debian 12: apt-get install clang-tidy)" >&2; exit 2; }
[ -f "$build/compile_commands.json" ] ||
  { echo "tidy: '$build' has no compile_commands.json (configure it with cmake first)" >&2; exit 2; }
for f in "${folders[@]}"; do
  [ -d "$root/$f" ] || { echo "tidy: no folder '$f' in $root" >&2; exit 2; }
done

out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
cd "$root"
mapfile -t files < <(find "${folders[@]}" -maxdepth 2 -name '*.cpp' | sort)
echo "tidy: ${#files[@]} files, $jobs at a time" >&2
filter="^$root/($(IFS='|'; echo "${folders[*]}"))/"
printf '%s\n' "${files[@]}" | xargs -P "$jobs" -I{} sh -c \
  '"$0" -p "$1" --quiet --header-filter="$2" "{}" > "$3/$(echo "{}" | tr / _).txt" 2>&1 || true' \
  "$program" "$build" "$filter" "$out"
findings="$(cat "$out"/*.txt | grep -E "^$root/[^:]+:[0-9]+:[0-9]+: (warning|error):" | sort -u || true)"
if [ -z "$findings" ]; then
  echo "tidy: no findings in ${#files[@]} files"
  exit 0
fi
printf '%s\n' "$findings" | sed "s|^$root/||"
echo
echo "tidy: $(printf '%s\n' "$findings" | wc -l) findings; per check:"
printf '%s\n' "$findings" | sed -n 's/.*\[\([^]]*\)\]$/\1/p' | sort | uniq -c | sort -rn
exit 1
