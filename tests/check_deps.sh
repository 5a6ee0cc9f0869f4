#!/usr/bin/env bash
# Checks which way #includes point (README "Layout", STYLE.md "Architecture"):
#   check_deps.sh [ROOT]      checks the tree at ROOT (default: the repository); prints each
#                             offending file:line and exits 1 when a rule is broken.
#   check_deps.sh --self-test checks a small fake tree with known bad includes and fails unless
#                             exactly those are reported.
# Applies to the product folders (the libraries and cli/); tests/ may include anything.
set -euo pipefail

# Project modules each folder may include (its own included). A C++ source in a top-level folder
# not listed here is an error: a new library folder must say where it sits.
module_rules=(
  "kinematics: kinematics"
  "collision:  kinematics collision"
  "scanner:    kinematics scanner"
  "planner:    kinematics collision planner"
  "pipeline:   kinematics collision scanner planner pipeline"
  "cli:        kinematics collision scanner planner pipeline cli"
)
# Third-party headers (an extended regex on the include path) and the only folder that may
# include them. A rule marked "headers" applies to headers only (yaml-cpp: the sweep reader in
# cli/batch/ parses YAML in its .cpp, but no header outside cli/config/ exposes yaml-cpp). A rule
# marked "pending" prints its violations but does not fail the check (for work not landed yet).
third_party_rules=(
  "fcl/            collision/"
  "embree[0-9]*/   scanner/"
  "nanoflann       scanner/"
  "glpk\.h         scanner/"
  "ompl/           planner/"
  "nlopt           planner/"
  "yaml-cpp/       cli/"
  "yaml-cpp/       cli/config/  headers"
  "urdf_           cli/config/"
  "console_bridge/ cli/config/"
  "CLI/            cli/"
  "png\.h          cli/"
)

check() {
  local root=$1 failed=0 pending=0
  local -A allowed=()
  local rule folder deps
  for rule in "${module_rules[@]}"; do
    folder=${rule%%:*}
    deps=${rule#*:}
    allowed[$folder]=$(echo $deps)
  done
  local modules="${!allowed[*]}"

  local files=()
  mapfile -t files < <(cd "$root" && find . -path ./tests -prune -o -path './build*' -prune \
                         -o -path './.*' -prune -o -type f \
                         \( -name '*.h' -o -name '*.hpp' -o -name '*.cpp' \) -print |
                         sed 's|^\./||' | LC_ALL=C sort)
  local file top line path target ok m
  for file in "${files[@]}"; do
    top=${file%%/*}
    if [ "$top" = "$file" ] || [ -z "${allowed[$top]+x}" ]; then
      echo "$file: in no module of tests/check_deps.sh (add its folder to module_rules)"
      failed=1
      continue
    fi
    while IFS=: read -r line path; do
      target=${path%%/*}
      ok=0
      for m in $modules; do [ "$m" = "$target" ] && ok=1; done
      ((ok)) || continue  # not a project module
      ok=0
      for m in ${allowed[$top]}; do [ "$m" = "$target" ] && ok=1; done
      if ((!ok)); then
        echo "$file:$line: $top/ includes $path ($top/ may include: ${allowed[$top]})"
        failed=1
      fi
    done < <(grep -nE '^[[:space:]]*#[[:space:]]*include[[:space:]]*["<]' "$root/$file" |
               sed -E 's/^([0-9]+):[^"<]*["<]([^">]*).*/\1:\2/' || true)
  done

  local pattern home flag hits hit
  for rule in "${third_party_rules[@]}"; do
    read -r pattern home flag <<<"$rule"
    hits=$(cd "$root" && for file in "${files[@]}"; do
             case $file in "$home"*) continue ;; esac
             [ "$flag" = headers ] && case $file in *.h | *.hpp) ;; *) continue ;; esac
             grep -nE "^[[:space:]]*#[[:space:]]*include[[:space:]]*<$pattern" "$file" |
               sed "s|^|$file:|" || true
           done)
    [ -z "$hits" ] && continue
    while IFS= read -r hit; do
      if [ "$flag" = pending ]; then
        echo "pending (not failing yet): ${hit%%:#*}: <$pattern…> outside $home"
        pending=1
      else
        echo "${hit%%:#*}: <$pattern…> may be included only in $home"
        failed=1
      fi
    done <<<"$hits"
  done

  ((failed)) && return 1
  echo "check_deps: includes point the right way in ${#files[@]} files$( ((pending)) &&
    echo ' (pending rules above not enforced yet)')"
}

self_test() {
  local tmp
  tmp=$(mktemp -d)
  trap 'rm -rf "$tmp"' RETURN
  mkdir -p "$tmp"/{kinematics,collision,planner,cli/config,tests}
  printf '#pragma once\n#include <vector>\n#include "kinematics/pose.h"\n' >"$tmp/kinematics/pose.h"
  printf '#include "kinematics/pose.h"\n#include <fcl/fcl.h>\n' >"$tmp/collision/scene.cpp"
  printf '#include "cli/app.h"\n' >"$tmp/tests/test_app.cpp"
  printf '#include <yaml-cpp/yaml.h>\n#include <CLI/CLI.hpp>\n' >"$tmp/cli/config/job.cpp"
  if ! check "$tmp" >"$tmp/out"; then
    cat "$tmp/out"; echo "self-test: a clean tree failed"; return 1
  fi
  printf '#pragma once\n\n#include "collision/scene.h"\n' >"$tmp/kinematics/bad.h"
  printf '#include "planner/x.h"\n  #  include "cli/app.h"\n#include <ompl/base/Goal.h>\n' \
    >"$tmp/collision/bad.cpp"
  printf '#include <fcl/fcl.h>\n#include <yaml-cpp/yaml.h>\n' >"$tmp/planner/bad.cpp"
  printf '#include <yaml-cpp/yaml.h>\n' >"$tmp/cli/bad.h"
  printf '#include <yaml-cpp/yaml.h>\n' >"$tmp/cli/fine.cpp"
  printf 'int x;\n' >"$tmp/stray.cpp"
  if check "$tmp" >"$tmp/out"; then
    cat "$tmp/out"; echo "self-test: a tree with bad includes passed"; return 1
  fi
  local expected
  for expected in 'collision/bad.cpp:1: collision/ includes planner/x.h' \
                  'collision/bad.cpp:2: collision/ includes cli/app.h' \
                  'kinematics/bad.h:3: kinematics/ includes collision/scene.h' \
                  'collision/bad.cpp:3: <ompl/' 'planner/bad.cpp:1: <fcl/' \
                  'planner/bad.cpp:2: <yaml-cpp/…> may be included only in cli/' \
                  'cli/bad.h:1: <yaml-cpp/…> may be included only in cli/config/' \
                  'stray.cpp: in no module'; do
    grep -qF "$expected" "$tmp/out" || {
      cat "$tmp/out"; echo "self-test: missing: $expected"; return 1
    }
  done
  [ "$(wc -l <"$tmp/out")" -eq 8 ] || { cat "$tmp/out"; echo "self-test: extra lines"; return 1; }
  echo "check_deps self-test: the bad includes were reported, the good ones were not"
}

if [ "${1:-}" = --self-test ]; then
  self_test
else
  check "${1:-$(cd "$(dirname "$0")/.." && pwd)}"
fi
