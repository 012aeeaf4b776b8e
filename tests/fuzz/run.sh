#!/usr/bin/env bash
# Runs each libFuzzer target of tests/fuzz for a fixed time over its committed seeds
# (corpus/<format>/) and regression files (regressions/<format>/), with the format's dictionary
# when there is one. A "format" is a target's name without fuzz_: a mesh format, text, or cut
# (fuzz_cut, whose input is a sequence of cuts and steps). New inputs go to
# BUILD/fuzz-work/<format>/corpus (kept between local runs, never into the committed corpus); a
# failing input goes to BUILD/fuzz-work/<format>/artifacts/.
# Prints one line per target; on a failure, the end of its log. Exits non-zero if any failed.
# Usage: tests/fuzz/run.sh BUILD SECONDS [FORMAT...]   (default: every format)
set -euo pipefail

if [ $# -lt 2 ]; then
  echo "usage: $0 BUILD SECONDS [FORMAT...]" >&2
  exit 2
fi
build=$1
seconds=$2
shift 2
formats=("$@")
[ ${#formats[@]} -gt 0 ] || formats=(gmsh vtk vtu tetgen text cut)
here=$(cd "$(dirname "$0")" && pwd)

# Stack traces for UBSan reports (which abort: the fuzzers are built with -fno-sanitize-recover).
export UBSAN_OPTIONS="print_stacktrace=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"

failed=()
for format in "${formats[@]}"; do
  work="$build/fuzz-work/$format"
  mkdir -p "$work/corpus" "$work/artifacts"
  # -timeout: an input that takes 10 s (the seeds take microseconds) is a hang.
  options=(-max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1
           -artifact_prefix="$work/artifacts/")
  [ -f "$here/$format.dict" ] && options+=(-dict="$here/$format.dict")
  inputs=("$work/corpus" "$here/corpus/$format")
  [ -d "$here/regressions/$format" ] && inputs+=("$here/regressions/$format")
  if "$build/tests/fuzz/fuzz_$format" "${options[@]}" "${inputs[@]}" > "$work/log" 2>&1; then
    echo "fuzz_$format: ${seconds} s, $(grep -m1 'DONE' "$work/log" | sed 's/^#[0-9]*[[:space:]]*DONE[[:space:]]*//')," \
      "$(grep -m1 'number_of_executed_units' "$work/log" | sed 's/.*: *//') inputs run"
  else
    failed+=("$format")
    echo "fuzz_$format FAILED; the end of $work/log:"
    tail -n 60 "$work/log"
    echo "failing input(s): $(ls "$work"/artifacts/* 2>/dev/null | tr '\n' ' ')"
  fi
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzz: failed: ${failed[*]} (reproduce: $build/tests/fuzz/fuzz_<format> <input>; see tests/fuzz/README.md)"
  exit 1
fi
echo "fuzz: ${#formats[@]} passed, 0 failed"
