#!/usr/bin/env bash
# Checks the code against the project's style: clang-format (.clang-format) on C and C++,
# ruff (ruff.toml: lint and format) on the Python of blender_addon/, docs/, python/, scripts/ and tests/,
# mypy (mypy.ini) on the typed modules, clang-tidy (.clang-tidy) on C and C++ sources with
# build/compile_commands.json, and the layout of core/src (scripts/check-layout.py: includes between
# its folders run one way).
#
#   scripts/check-style.sh          the lines changed since the base: what a commit must keep clean
#   scripts/check-style.sh --all    every file, every line (the tree is not reformatted yet)
#   scripts/check-style.sh --fix    reformat the changed lines in place (clang-format, ruff format)
#
# The base is $DQJ_STYLE_BASE, else the merge-base of HEAD with main, or HEAD~1 when HEAD is
# main itself or there is no main; changes not committed yet count too. ruff's lint and
# clang-tidy report only findings on changed lines, so old code does not block new; mypy checks
# the typed modules whole, every run (a type crosses lines and files).
# Tools: clang-format and clang-tidy from Debian (scripts/install-deps.sh), ruff and mypy from
# scripts/tool-env.sh; DQJ_CLANG_FORMAT, DQJ_CLANG_TIDY, DQJ_RUFF, DQJ_MYPY name others,
# DQJ_BUILD_DIR another build tree. A missing tool is reported and skipped (DQJ_TEST_SKIPPED, as the tests
# say it), except under CI=true, where it fails.
# Exit status: 0 clean, 1 findings (or a missing tool in CI), 2 usage.
set -euo pipefail
cd "$(dirname "$0")/.."

mode=changed
case "${1:-}" in
  "") ;;
  --all) mode=all ;;
  --fix) mode=fix ;;
  *) echo "usage: check-style.sh [--all | --fix]" >&2; exit 2 ;;
esac

clang_format="${DQJ_CLANG_FORMAT:-clang-format}"
clang_tidy="${DQJ_CLANG_TIDY:-clang-tidy}"
ruff="${DQJ_RUFF:-$(scripts/tool-env.sh ruff --print || true)}"
mypy="${DQJ_MYPY:-$(scripts/tool-env.sh mypy --print || true)}"
build="${DQJ_BUILD_DIR:-build}"
jobs="$(nproc)"

failed=0
skipped=""
missing() {  # the project's rule for a missing tool (tests/script_support.cmake)
  if [ "${CI:-}" = "true" ]; then
    echo "check-style: $1 (CI=true: every check must run)" >&2
    failed=1
  else
    echo "DQJ_TEST_SKIPPED: $1"
    skipped=" (but not every check ran)"
  fi
}
have() { command -v "$1" >/dev/null 2>&1; }

is_cxx() { case "$1" in *.c | *.cpp | *.h | *.hpp) return 0 ;; esac; return 1; }
is_python() { case "$1" in blender_addon/*.py | docs/*.py | python/*.py | scripts/*.py | tests/*.py) return 0 ;; esac; return 1; }

# The files to check and, unless --all, the lines changed in each ("FIRST:LAST" ranges).
declare -A ranges=()
files=()
if [ "$mode" = all ]; then
  while IFS= read -r file; do files+=("$file"); done < <(git ls-files)
  base="(none: every line)"
else
  base="${DQJ_STYLE_BASE:-}"
  if [ -z "$base" ]; then
    base="$(git merge-base HEAD main 2>/dev/null || true)"
    if [ -z "$base" ] || [ "$base" = "$(git rev-parse HEAD)" ]; then
      base="$(git rev-parse --verify -q HEAD~1 || true)"
    fi
  fi
  if [ -z "$base" ]; then
    echo "check-style: no base commit to compare with (set DQJ_STYLE_BASE, or use --all): nothing checked"
    exit 0
  fi
  # New lines of each hunk, from "@@ -a,b +c,d @@" (d = 0: lines only removed), in one diff with
  # rename detection (-M), so a moved file's changed lines are its edits, not all its lines.
  while read -r file range; do
    [ -f "$file" ] || continue
    [ -n "${ranges[$file]+set}" ] || files+=("$file")
    ranges[$file]="${ranges[$file]:-}${range:+$range }"
  done < <(git diff -U0 -M --no-color --diff-filter=d "$base" |
    awk '/^\+\+\+ / { file = substr($0, 7); print file, ""; next }
         /^@@ / { split($3, new, ","); n = (new[2] == "") ? 1 : new[2]; first = substr(new[1], 2)
                  if (n > 0) printf "%s %d:%d \n", file, first, first + n - 1 }')
  while IFS= read -r file; do
    [ -f "$file" ] && [ -z "${ranges[$file]+set}" ] && files+=("$file")
  done < <(git ls-files --others --exclude-standard)
  for file in $(git ls-files --others --exclude-standard); do
    ranges[$file]="1:$(($(wc -l < "$file") + 1))"
  done
fi
cxx=() python=()
for file in "${files[@]}"; do
  if is_cxx "$file"; then cxx+=("$file"); elif is_python "$file"; then python+=("$file"); fi
done
echo "check-style: ${#cxx[@]} C/C++ and ${#python[@]} Python files, against ${base}"

# clang-format: --lines for each changed range; whole files with --all.
if [ ${#cxx[@]} -gt 0 ]; then
  if ! have "$clang_format"; then
    missing "clang-format is not installed (scripts/install-deps.sh installs it)"
  else
    for file in "${cxx[@]}"; do
      arguments=()
      if [ "$mode" != all ]; then
        [ -n "${ranges[$file]// /}" ] || continue
        for range in ${ranges[$file]}; do arguments+=("--lines=$range"); done
      fi
      if [ "$mode" = fix ]; then
        "$clang_format" -i "${arguments[@]}" "$file"
      elif ! "$clang_format" --dry-run --Werror "${arguments[@]}" "$file"; then
        failed=1
      fi
    done
  fi
fi

# The project's own rule: no thread_local with a destructor in the library or the command. With
# MinGW-w64 one corrupts the heap when its thread exits (GCC bug 80816); per-thread buffers are
# ThreadScratch (core/src/platform/thread_scratch.hpp). A thread_local of a trivially destructible type says
# so on its line or the line before ("trivially destructible").
in_ranges() {  # in_ranges FILE LINE: whether LINE is among FILE's changed lines (always with --all)
  [ "$mode" = all ] && return 0
  local range
  for range in ${ranges[$1]:-}; do
    [ "$2" -ge "${range%%:*}" ] && [ "$2" -le "${range##*:}" ] && return 0
  done
  return 1
}
for file in "${cxx[@]}"; do
  case "$file" in core/*) ;; *) continue ;; esac
  while IFS=: read -r line text; do
    if in_ranges "$file" "$line"; then
      echo "$file:$line: thread_local with a destructor breaks Windows builds; use ThreadScratch, or say" \
        "\"trivially destructible\" on the line: $text"
      failed=1
    fi
  done < <(awk '/(^|[^A-Za-z0-9_])thread_local([^A-Za-z0-9_]|$)/ && !/trivially destructible/ && previous !~ /trivially destructible/ { print FNR ":" $0 }
                { previous = $0 }' "$file")
done

# ruff: lint findings on changed lines; format per changed range (ruff formats one range a run).
if [ ${#python[@]} -gt 0 ]; then
  if [ -z "$ruff" ] || ! have "$ruff"; then
    missing "ruff is not installed (scripts/tool-env.sh ruff installs it)"
  else
    if [ "$mode" = all ]; then
      "$ruff" check --quiet --output-format concise "${python[@]}" || failed=1
      "$ruff" format --check "${python[@]}" || failed=1
    else
      findings="$("$ruff" check --quiet --output-format concise --exit-zero "${python[@]}")"
      while IFS= read -r finding; do
        [ -n "$finding" ] || continue
        file="${finding%%:*}" rest="${finding#*:}" line="${rest%%:*}"
        if in_ranges "$file" "$line"; then
          echo "$finding"
          failed=1
        fi
      done <<< "$findings"
      for file in "${python[@]}"; do
        for range in ${ranges[$file]:-}; do
          if [ "$mode" = fix ]; then
            "$ruff" format --quiet --range "${range/:/-}" "$file"
          elif ! "$ruff" format --quiet --diff --range "${range/:/-}" "$file"; then
            failed=1
          fi
        done
      done
    fi
  fi
fi

# mypy: the typed modules (mypy.ini says which and why), checked as the add-on's package holds
# them: its modules with native.py, the copy the packaging makes of python/dqjulia/_native.py
# (blender_addon/package.cmake), in a staging folder; findings name the files of the tree.
typed=(native.py jobs.py)
if [ "$mode" != fix ]; then
  if [ -z "$mypy" ] || ! have "$mypy"; then
    missing "mypy is not installed (scripts/tool-env.sh mypy installs it)"
  else
    stage="$(mktemp -d)"
    mkdir "$stage/dqjulia"
    cp blender_addon/dqjulia/*.py "$stage/dqjulia/"
    cp python/dqjulia/_native.py "$stage/dqjulia/native.py"
    if ! (cd "$stage" && "$mypy" --config-file "$OLDPWD/mypy.ini" --cache-dir /dev/null "${typed[@]/#/dqjulia/}") \
      >"$stage/report" 2>&1; then
      sed -e 's|^dqjulia/native\.py:|python/dqjulia/_native.py:|' -e 's|^dqjulia/|blender_addon/dqjulia/|' "$stage/report"
      failed=1
    else
      echo "check-style: mypy: ${typed[*]} clean"
    fi
    rm -rf "$stage"
  fi
fi

# clang-tidy: the sources in compile_commands.json; with a line filter unless --all.
if [ ${#cxx[@]} -gt 0 ] && [ "$mode" != fix ]; then
  if ! have "$clang_tidy"; then
    missing "clang-tidy is not installed (scripts/install-deps.sh installs it)"
  elif [ ! -f "$build/compile_commands.json" ]; then
    missing "$build/compile_commands.json is missing (scripts/build.sh makes it)"
  else
    sources=()
    for file in "${cxx[@]}"; do
      case "$file" in *.c | *.cpp) grep -q "\"file\": \"$PWD/$file\"" "$build/compile_commands.json" && sources+=("$file") ;; esac
    done
    filter=()
    if [ "$mode" != all ]; then
      entries=()
      for file in "${cxx[@]}"; do
        pairs=()
        for range in ${ranges[$file]:-}; do pairs+=("[${range%%:*},${range##*:}]"); done
        [ ${#pairs[@]} -eq 0 ] || entries+=("{\"name\":\"$file\",\"lines\":[$(IFS=,; echo "${pairs[*]}")]}")
      done
      # An empty list would mean every line: name a line no file has instead.
      [ ${#entries[@]} -gt 0 ] || entries+=('{"name":"-","lines":[[1,1]]}')
      filter=("--line-filter=[$(IFS=,; echo "${entries[*]}")]")
    fi
    if [ ${#sources[@]} -gt 0 ]; then
      started=$SECONDS
      report="$(mktemp)"
      printf '%s\n' "${sources[@]}" |
        xargs -P "$jobs" -I{} "$clang_tidy" -p "$build" --quiet "${filter[@]}" {} >"$report" 2>/dev/null || true
      if grep -q ": \(warning\|error\):" "$report"; then
        cat "$report"
        echo "check-style: clang-tidy: $(grep -c ": \(warning\|error\):" "$report") findings"
        failed=1
      fi
      rm -f "$report"
      echo "check-style: clang-tidy checked ${#sources[@]} sources in $((SECONDS - started)) s"
    fi
  fi
fi

# The layout: includes between the folders of core/src run one way (CONTRIBUTING.md, Layout);
# the whole tree each time (it takes a moment), and the check's own self-test.
python3 scripts/check-layout.py || failed=1
python3 scripts/check-layout.py --self-test >/dev/null || { python3 scripts/check-layout.py --self-test; failed=1; }

if [ "$failed" -ne 0 ]; then
  echo "check-style: FAILED (scripts/check-style.sh --fix reformats the changed lines; CONTRIBUTING.md, Style)" >&2
  exit 1
fi
echo "check-style: clean$skipped"
