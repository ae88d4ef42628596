#!/usr/bin/env bash
# Checks that every C++ file of the project (.cpp and .hpp under the source folders) is as
# .clang-format lays it out, with clang-format 14 (Debian 12's; other versions lay some
# constructs out differently).
#
#   scripts/check_format.sh          list the files that differ and show the first differences;
#                                    exit 1 when any does
#   scripts/check_format.sh --fix    format them in place
#
# CLANG_FORMAT names the program (default: clang-format-14, else clang-format). Exit status 77
# (ctest's skip) when it is missing or not version 14.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
fix=0
case "${1:-}" in
  "") ;;
  --fix) fix=1 ;;
  -h | --help)
    sed -n '2,12p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'
    exit 0
    ;;
  *)
    echo "check_format: unknown option '$1' (use --fix or --help)" >&2
    exit 2
    ;;
esac

program="${CLANG_FORMAT:-}"
if [ -z "$program" ]; then
  program="$(command -v clang-format-14 || command -v clang-format || true)"
fi
if [ -z "$program" ] || ! command -v "$program" > /dev/null; then
  echo "check_format: clang-format not found (Debian 12: apt-get install clang-format; scripts/install_dependencies.sh installs it)" >&2
  exit 77
fi
version="$("$program" --version)"
if ! [[ "$version" =~ version\ 14\. ]]; then
  echo "check_format: the layout is clang-format 14's; $program is: $version" >&2
  exit 77
fi

folders=(batch collision common remesh scenegen simulation tests validation)
mapfile -d '' files < <(cd "$root" && find "${folders[@]}" -type f \( -name '*.cpp' -o -name '*.hpp' \) -print0 | sort -z)
if [ ${#files[@]} -eq 0 ]; then
  echo "check_format: no C++ files under $root" >&2
  exit 2
fi

cd "$root"
if [ $fix -eq 1 ]; then
  "$program" -i --style=file "${files[@]}"
  echo "check_format: formatted ${#files[@]} files"
  exit 0
fi
# One clang-format for every file: --dry-run names each place that differs as
# "FILE:LINE:COL: error: code should be clang-formatted".
report="$("$program" --style=file --dry-run --Werror "${files[@]}" 2>&1)" && status=0 || status=$?
mapfile -t differ < <(printf '%s\n' "$report" | sed -n 's/^\(.*\):[0-9]*:[0-9]*: error: code should be clang-formatted.*/\1/p' | sort -u)
if [ $status -ne 0 ] && [ ${#differ[@]} -eq 0 ]; then
  printf '%s\n' "$report" >&2
  echo "check_format: $program failed (status $status)" >&2
  exit 2
fi
if [ ${#differ[@]} -eq 0 ]; then
  echo "check_format: ${#files[@]} files follow .clang-format"
  exit 0
fi
echo "check_format: ${#differ[@]} of ${#files[@]} files differ from .clang-format (scripts/check_format.sh --fix formats them):"
printf '  %s\n' "${differ[@]}"
for f in "${differ[@]:0:3}"; do
  "$program" --style=file "$f" | diff -u --label "$f" --label "$f (formatted)" "$f" - | head -40 || true
done
exit 1
