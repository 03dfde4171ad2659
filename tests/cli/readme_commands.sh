#!/usr/bin/env bash
# Runs every command the README shows, as a user would after README command 1, and fails on any
# non-zero exit.
#
# Usage: readme_commands.sh BUILD_DIR SOURCE_DIR [PAGE.md ...]
#   BUILD_DIR   the build whose tests run this (it holds apps/sinscal)
#   SOURCE_DIR  the repository root
#   PAGE.md     further pages (or folders of pages) whose commands to run after the README's,
#               relative to SOURCE_DIR (e.g. docs/usage), in the same working folder
#
# The commands are read from the pages themselves, so that a page and its test cannot drift: every
# line of a ```sh block, and the command of every row of the README's task table (the inline code
# that starts with ./build/apps/sinscal). They run in order, each in `bash -c` with pipefail, from a
# working folder that stands for the repository root: BUILD_DIR/readme_commands, holding symbolic
# links to the repository's folders (config, data, ...) and `build` -> BUILD_DIR, and its own `out/`
# (the repository's is never written); with further pages, BUILD_DIR/readme_commands-NNN.
#
# README command 1 installs the Debian packages, builds, then runs the main job. Here its apt-get
# part is checked instead of run (every package it installs must be installed: dpkg -s), and its
# build is the build this test belongs to: its cmake steps must be README command 2's, which built
# BUILD_DIR. README command 2 (build and ctest) is what CI runs; running it here would run this
# test inside itself, so each of its steps is checked to be in .ci/run instead.
set -u
if [ $# -lt 2 ]; then
  echo "usage: $0 BUILD_DIR SOURCE_DIR [PAGE.md ...]" >&2
  exit 2
fi
build=$(cd "$1" && pwd) || exit 2
src=$(cd "$2" && pwd) || exit 2
shift 2
pages=()
for page in "$@"; do  # a folder stands for its pages, in name order
  if [ -d "$src/$page" ]; then
    for f in "$src/$page"/*.md; do [ -e "$f" ] && pages+=("${f#"$src"/}"); done
  else
    pages+=("$page")
  fi
done
# Its own working folder per set of pages, so that two such tests can run at once.
work=$build/readme_commands
[ ${#pages[@]} -eq 0 ] || work=$build/readme_commands-$(printf '%s\n' "${pages[@]}" | cksum | cut -d' ' -f1)
rm -rf "$work"
mkdir -p "$work/out"
pass=0
fail=0
failed() { fail=$((fail + 1)); echo "FAILED: $*" >&2; }

if [ ! -x "$build/apps/sinscal" ]; then
  echo "FAILED: $build/apps/sinscal is not built"
  exit 1
fi

# The working folder: the repository's folders as links, the build under test as ./build.
for entry in "$src"/*; do
  [ -e "$entry" ] || continue
  name=$(basename "$entry")
  case $name in build | build-* | out) continue ;; esac
  ln -s "$entry" "$work/$name"
done
ln -s "$build" "$work/build"

# commands_of PAGE: one command per line, in the page's order: the lines of its ```sh blocks and the
# ./build/apps/sinscal command of each table row. A table row of the README's task table without a
# command is printed as "MISSING <row>".
commands_of() {
  awk -v readme="$(basename "$1")" '
    /^```sh[[:space:]]*$/ { in_sh = 1; next }
    /^```/ { in_sh = 0; next }
    in_sh { if ($0 !~ /^[[:space:]]*$/) print; next }
    /^## / { tasks = ($0 == "## Tasks") }
    /^\|/ {
      if ($0 ~ /^\|[-| ]+\|?[[:space:]]*$/ || $0 ~ /^\| *task *\|/) next
      line = $0; found = 0
      while (match(line, /`\.\/build\/apps\/sinscal [^`]*`/)) {
        print substr(line, RSTART + 1, RLENGTH - 2); found = 1
        line = substr(line, RSTART + RLENGTH)
      }
      if (!found && tasks && readme == "README.md") print "MISSING " $0
    }
  ' "$1"
}

# README command 1: `S=...; $S apt-get update && $S apt-get install -y PACKAGES && cmake ... &&
# cmake --build ... && the main job`. Prints the main job's commands, one per line; checks the rest.
command1_parts() {
  local part rest=$1
  local -a parts=()
  while [[ $rest == *" && "* ]]; do
    parts+=("${rest%% && *}")
    rest=${rest#* && }
  done
  parts+=("$rest")
  for part in "${parts[@]}"; do
    case $part in
      *"apt-get update"*) ;;
      *"apt-get install"*)
        local packages=${part#*apt-get install -y }
        if command -v dpkg >/dev/null 2>&1; then
          # shellcheck disable=SC2086
          if dpkg -s $packages >/dev/null 2>&1; then
            pass=$((pass + 1))
          else
            failed "README command 1's packages are not all installed: $packages"
          fi
        else
          echo "note: no dpkg here; README command 1's packages not checked" >&2
        fi
        ;;
      cmake*)
        if [[ " && $command2 && " == *" && $part && "* ]]; then
          pass=$((pass + 1))
        else
          failed "README command 1 builds with '$part', which README command 2 does not: the build under test is not command 1's"
        fi
        ;;
      *) printf '%s\n' "$part" ;;
    esac
  done
}

readme=$src/README.md
mapfile -t readme_commands < <(commands_of "$readme")
command1=""
command2=""
for c in "${readme_commands[@]}"; do
  case $c in
    "S=\$("*"apt-get install"*) command1=$c ;;
    "cmake -S "*"ctest "*) command2=$c ;;
  esac
done
if [ -z "$command1" ] || [ -z "$command2" ]; then
  failed "README.md: command 1 (install, build, main job) or command 2 (build and tests) not found"
  echo "$pass passed, $fail failed"
  exit 1
fi

# README command 2: every step of it is in .ci/run, which runs it on a clean clone.
rest=$command2
while :; do
  step=${rest%% && *}
  if grep -qF -- "$step" "$src/.ci/run"; then
    pass=$((pass + 1))
  else
    failed "README command 2's step '$step' is not in .ci/run"
  fi
  [[ $rest == *" && "* ]] || break
  rest=${rest#* && }
done

# The commands to run: command 1's main job, then the README's other commands, then the pages'.
to_run=()
# (not in a subshell: its checks count)
command1_parts "$command1" > "$work/main_job.txt"
mapfile -t main_job < "$work/main_job.txt"
to_run+=("${main_job[@]}")
for c in "${readme_commands[@]}"; do
  [ "$c" = "$command1" ] || [ "$c" = "$command2" ] && continue
  to_run+=("$c")
done
for page in "${pages[@]}"; do
  [ -f "$src/$page" ] || { failed "$page: no such page"; continue; }
  mapfile -t page_commands < <(commands_of "$src/$page")
  to_run+=("${page_commands[@]}")
done

n=0
for c in "${to_run[@]}"; do
  if [[ $c == MISSING* ]]; then
    failed "README.md: a task row without a ./build/apps/sinscal command: ${c#MISSING }"
    continue
  fi
  n=$((n + 1))
  log=$work/command-$n.log
  start=$SECONDS
  (cd "$work" && bash -c "set -o pipefail; $c") > "$log" 2>&1
  rc=$?
  if [ $rc -eq 0 ]; then
    pass=$((pass + 1))
    echo "ok $n ($((SECONDS - start)) s): $c"
  else
    failed "exit $rc ($((SECONDS - start)) s): $c"
    tail -n 20 "$log" | sed 's/^/    /'
  fi
done
if [ $n -lt 12 ]; then
  failed "only $n commands found to run: README.md's commands were not all read"
fi

echo "$pass passed, $fail failed"
test "$fail" -eq 0
