#!/usr/bin/env bash
# Checks that no function of the product (the libraries and cli/) is longer than a screen:
#   check_function_length.sh [ROOT] [MAX]  lists every function over MAX lines (default 80), from
#                                          its signature's first line to its closing brace, and
#                                          exits 1 when there is one;
#   check_function_length.sh --self-test   checks a small fake tree with a known long function and
#                                          fails unless exactly that one is reported.
# Universal Ctags finds the functions (with their end lines); without it the check cannot run.
set -euo pipefail

folders=(kinematics collision scanner planner pipeline programs config cli python)

check() {
  local root=$1 max=$2
  if ! command -v ctags >/dev/null; then
    echo "check_function_length: skipped: universal-ctags is not installed"
    return 77  # ctest's SKIP_RETURN_CODE
  fi
  local present=() f
  for f in "${folders[@]}"; do [ -d "$root/$f" ] && present+=("$f"); done
  local long
  long=$(cd "$root" && ctags -f - --languages=C++ --kinds-C++=f --fields=+ne -R "${present[@]}" |
    awk -F'\t' -v max="$max" '{
      first = 0; last = 0
      for (i = 4; i <= NF; i++) {
        if ($i ~ /^line:/) first = substr($i, 6)
        if ($i ~ /^end:/) last = substr($i, 5)
      }
      if (last - first + 1 > max) printf "%s:%d: %s is %d lines (at most %d)\n", $2, first, $1, last - first + 1, max
    }' | LC_ALL=C sort)
  if [ -n "$long" ]; then
    echo "$long"
    return 1
  fi
  echo "check_function_length: no function over $max lines"
}

self_test() {
  command -v ctags >/dev/null || { echo "self-test skipped: no universal-ctags"; return 77; }
  local tmp
  tmp=$(mktemp -d)
  trap 'rm -rf "$tmp"' RETURN
  mkdir -p "$tmp/planner" "$tmp/tests"
  {
    printf 'int shortOne() {\n  return 1;\n}\n\n'
    printf 'int longOne(int x) {\n'
    for i in $(seq 1 80); do printf '  x += %d;\n' "$i"; done
    printf '  return x;\n}\n'
  } >"$tmp/planner/a.cpp"
  {
    printf 'int inTests() {\n'
    for i in $(seq 1 100); do printf '  ;\n'; done
    printf '}\n'
  } >"$tmp/tests/t.cpp"
  local out
  out=$(check "$tmp" 80) && { echo "$out"; echo "self-test: a long function passed"; return 1; }
  [ "$out" = "planner/a.cpp:5: longOne is 83 lines (at most 80)" ] ||
    { echo "$out"; echo "self-test: expected exactly longOne"; return 1; }
  echo "check_function_length self-test: the long function was reported, the others were not"
}

if [ "${1:-}" = --self-test ]; then
  self_test
else
  check "${1:-$(cd "$(dirname "$0")/.." && pwd)}" "${2:-80}"
fi
