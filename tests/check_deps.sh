#!/usr/bin/env bash
# Checks which way #includes point (docs/library.md "Layout"):
#   check_deps.sh [ROOT]      checks the tree at ROOT (default: the repository); prints each
#                             offending file:line and exits 1 when a rule is broken.
#   check_deps.sh --self-test checks a small fake tree with known bad includes and fails unless
#                             exactly those are reported.
# Applies to the product folders (the libraries and cli/); tests/ may include anything.
set -euo pipefail

# Project modules each folder may include (its own included), in dependency order. A C++ source
# in a top-level folder not listed here is an error: a new library folder must say where it sits.
# A library's headers are included as <scanplan/<library>/…> everywhere, never by a quoted path;
# the two front ends on top, cli/ and python/, include their own headers by quoted paths.
module_rules=(
  "kinematics: kinematics"
  "collision:  kinematics collision"
  "scanner:    kinematics scanner"
  "planner:    kinematics collision planner"
  "pipeline:   kinematics collision scanner planner pipeline"
  "programs:   kinematics programs"
  "config:     kinematics collision scanner planner pipeline programs config"
  "cli:        kinematics collision scanner planner pipeline programs config cli"
  "python:     kinematics collision scanner planner pipeline programs config cli python"
)
# Of cli/, python/ includes only the plan folder's writer (Plan.write() writes what `plan` writes).
python_from_cli="cli/commands/plan_folder.h"
# The folders inside cli/ and what each may include of cli/, in order: files, figures, reports,
# commands, batch runs. cli/'s own top-level files (app, completion, main) may include any.
cli_rules=(
  "io:       io"
  "plot:     io plot"
  "report:   io plot report"
  "commands: io plot report commands"
  "batch:    io plot report commands batch"
)
# Third-party headers (an extended regex on the include path) and the only folders (separated by
# commas) that may include them. A rule marked "headers" applies to headers only (yaml-cpp: the sweep reader in
# cli/batch/ parses YAML in its .cpp, but no header outside config/ exposes yaml-cpp). A rule
# marked "pending" prints its violations but does not fail the check (for work not landed yet).
third_party_rules=(
  "fcl/            collision/"
  "embree[0-9]*/   scanner/"
  "nanoflann       scanner/"
  "glpk\.h         scanner/"
  "ompl/           planner/"
  "nlopt           planner/"
  "yaml-cpp/       config/,cli/batch/"
  "yaml-cpp/       config/  headers"
  "urdf_           config/"
  "console_bridge/ config/"
  "CLI/            cli/"
  "pybind11/       python/"
  "png\.h          cli/"
)

# "a: b c" rules into the associative array named $2: a → "b c".
read_rules() {
  local -n rules=$1 into=$2
  local rule
  for rule in "${rules[@]}"; do
    into[${rule%%:*}]=$(echo ${rule#*:})
  done
}

# Prints line:path for each #include of $1, and "line:quoted:path" for quoted ones.
includes_of() {
  grep -nE '^[[:space:]]*#[[:space:]]*include[[:space:]]*["<]' "$1" |
    sed -E 's/^([0-9]+):[^"<]*"([^"]*)".*/\1:quoted:\2/; s/^([0-9]+):[^"<]*<([^>]*)>.*/\1:\2/' ||
    true
}

# "$top/ may include $target/": 0 or 1, from the module rules and, inside cli/, the cli rules.
allowed_include() {
  local file=$1 target=$2 m
  for m in ${allowed[$top]}; do [ "$m" = "$target" ] && return 0; done
  return 1
}

check_file() {
  local file=$1 line kind path target sub subtarget m ok
  while IFS=: read -r line kind path; do
    [ -z "$path" ] && { path=$kind; kind=angle; }
    target=${path%%/*}
    if [ "$kind" = angle ]; then
      [ "$target" = scanplan ] || continue  # a system or third-party header
      path=${path#scanplan/}
      target=${path%%/*}
    elif [ -n "${libraries[$target]+x}" ]; then
      echo "$file:$line: \"$path\": include a library header as <scanplan/$path>"
      failed=1
    fi
    [ -n "${allowed[$target]+x}" ] || continue  # not a project module
    if ! allowed_include "$file" "$target"; then
      echo "$file:$line: $top/ includes $path ($top/ may include: ${allowed[$top]})"
      failed=1
      continue
    fi
    if [ "$top" = python ] && [ "$target" = cli ] && [ "$path" != "$python_from_cli" ]; then
      echo "$file:$line: python/ includes $path (of cli/ only $python_from_cli)"
      failed=1
      continue
    fi
    # Inside cli/: its folders in their order.
    [ "$top" = cli ] && [ "$target" = cli ] || continue
    sub=${file#cli/}; sub=${sub%%/*}
    [ "$sub" = "${file#cli/}" ] && continue  # cli/'s own files include any part of cli/
    subtarget=${path#cli/}; subtarget=${subtarget%%/*}
    if [ -z "${cli_allowed[$sub]+x}" ]; then
      echo "$file: cli/$sub/ is in no rule of tests/check_deps.sh (add it to cli_rules)"
      failed=1
      continue
    fi
    ok=0
    for m in ${cli_allowed[$sub]}; do [ "$m" = "$subtarget" ] && ok=1; done
    if ((!ok)); then
      echo "$file:$line: cli/$sub/ includes $path (cli/$sub/ may include: ${cli_allowed[$sub]})"
      failed=1
    fi
  done < <(includes_of "$root/$file")
}

check() {
  local root=$1 failed=0 pending=0
  local -A allowed=() cli_allowed=() libraries=()
  read_rules module_rules allowed
  read_rules cli_rules cli_allowed
  local m
  for m in "${!allowed[@]}"; do
    case $m in cli | python) ;; *) libraries[$m]=1 ;; esac  # front ends: quoted includes
  done

  local files=()
  mapfile -t files < <(cd "$root" && find . -path ./tests -prune -o -path './build*' -prune \
                         -o -path './.*' -prune -o -type f \
                         \( -name '*.h' -o -name '*.hpp' -o -name '*.cpp' \) -print |
                         sed 's|^\./||' | LC_ALL=C sort)
  local file top
  for file in "${files[@]}"; do
    top=${file%%/*}
    if [ "$top" = "$file" ] || [ -z "${allowed[$top]+x}" ]; then
      echo "$file: in no module of tests/check_deps.sh (add its folder to module_rules)"
      failed=1
      continue
    fi
    check_file "$file"
  done

  local rule pattern homes flag hits hit home inside
  for rule in "${third_party_rules[@]}"; do
    read -r pattern homes flag <<<"$rule"
    hits=$(cd "$root" && for file in "${files[@]}"; do
             inside=0
             for home in ${homes//,/ }; do case $file in "$home"*) inside=1 ;; esac; done
             ((inside)) && continue
             [ "$flag" = headers ] && case $file in *.h | *.hpp) ;; *) continue ;; esac
             grep -nE "^[[:space:]]*#[[:space:]]*include[[:space:]]*<$pattern" "$file" |
               sed "s|^|$file:|" || true
           done)
    [ -z "$hits" ] && continue
    while IFS= read -r hit; do
      if [ "$flag" = pending ]; then
        echo "pending (not failing yet): ${hit%%:#*}: <$pattern…> outside ${homes//,/ and }"
        pending=1
      else
        echo "${hit%%:#*}: <$pattern…> may be included only in ${homes//,/ and }"
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
  mkdir -p "$tmp"/{kinematics,collision,planner,config,cli/io,cli/plot,cli/batch,python,tests}
  printf '#pragma once\n#include <vector>\n#include <scanplan/kinematics/pose.h>\n' \
    >"$tmp/kinematics/pose.h"
  printf '#include <scanplan/kinematics/pose.h>\n#include <fcl/fcl.h>\n' >"$tmp/collision/scene.cpp"
  printf '#include "cli/app.h"\n#include "kinematics/pose.h"\n' >"$tmp/tests/test_app.cpp"
  printf '#include <yaml-cpp/yaml.h>\n#include <CLI/CLI.hpp>\n' >"$tmp/cli/batch/sweep.cpp"
  printf '#include <yaml-cpp/yaml.h>\n#include <scanplan/planner/x.h>\n' >"$tmp/config/job.cpp"
  printf '#include "cli/io/output.h"\n#include <scanplan/config/job.h>\n' >"$tmp/cli/plot/figure.cpp"
  printf '#include "cli/commands/plan_folder.h"\n#include "python/run.h"\n' >"$tmp/python/plan.cpp"
  if ! check "$tmp" >"$tmp/out"; then
    cat "$tmp/out"; echo "self-test: a clean tree failed"; return 1
  fi
  printf '#pragma once\n\n#include <scanplan/collision/scene.h>\n' >"$tmp/kinematics/bad.h"
  printf '#include <scanplan/planner/x.h>\n  #  include "cli/app.h"\n#include <ompl/base/Goal.h>\n' \
    >"$tmp/collision/bad.cpp"
  printf '#include <fcl/fcl.h>\n#include <yaml-cpp/yaml.h>\n#include "kinematics/pose.h"\n' \
    >"$tmp/planner/bad.cpp"
  printf '#include <yaml-cpp/yaml.h>\n' >"$tmp/cli/bad.h"
  printf '#include <yaml-cpp/yaml.h>\n' >"$tmp/cli/plot/bad.cpp"
  printf '#include "cli/plot/figure.h"\n' >"$tmp/cli/io/bad.cpp"
  printf '#include "cli/io/output.h"\n' >"$tmp/python/bad.cpp"
  printf 'int x;\n' >"$tmp/stray.cpp"
  if check "$tmp" >"$tmp/out"; then
    cat "$tmp/out"; echo "self-test: a tree with bad includes passed"; return 1
  fi
  local expected
  for expected in 'collision/bad.cpp:1: collision/ includes planner/x.h' \
                  'collision/bad.cpp:2: collision/ includes cli/app.h' \
                  'kinematics/bad.h:3: kinematics/ includes collision/scene.h' \
                  'collision/bad.cpp:3: <ompl/' 'planner/bad.cpp:1: <fcl/' \
                  'planner/bad.cpp:2: <yaml-cpp/…> may be included only in config/ and cli/batch/' \
                  'planner/bad.cpp:3: "kinematics/pose.h": include a library header as <scanplan/' \
                  'cli/bad.h:1: <yaml-cpp/…> may be included only in config/' \
                  'cli/plot/bad.cpp:1: <yaml-cpp/…> may be included only in config/ and cli/batch/' \
                  'cli/io/bad.cpp:1: cli/io/ includes cli/plot/figure.h' \
                  'python/bad.cpp:1: python/ includes cli/io/output.h' \
                  'stray.cpp: in no module'; do
    grep -qF "$expected" "$tmp/out" || {
      cat "$tmp/out"; echo "self-test: missing: $expected"; return 1
    }
  done
  [ "$(wc -l <"$tmp/out")" -eq 13 ] || { cat "$tmp/out"; echo "self-test: extra lines"; return 1; }
  echo "check_deps self-test: the bad includes were reported, the good ones were not"
}

if [ "${1:-}" = --self-test ]; then
  self_test
else
  check "${1:-$(cd "$(dirname "$0")/.." && pwd)}"
fi
