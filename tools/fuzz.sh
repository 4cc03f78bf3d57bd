#!/usr/bin/env bash
# Runs the libFuzzer targets (tests/fuzz), built in the AddressSanitizer + UBSan tree (preset asan).
#
#   bash tools/fuzz.sh [seconds per target] [target...]     e.g. bash tools/fuzz.sh 600 fuzz_video
#
# Each target starts from its committed seed corpus tests/fuzz/corpus/<target>/ (regression inputs
# included) plus what earlier runs found (build/fuzz/corpus/<target>/, kept between runs). A crash,
# leak, sanitizer report or timeout stops that target, leaves the input in build/fuzz/crashes/ and
# makes the script exit 1 after all targets ran; add the input to the seed corpus once fixed.
# Default: 20 s per target, one target per core at a time. The last line per target says how many
# inputs it survived.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-20}
shift || true
cmake --preset asan >/dev/null
cmake --build --preset asan --target fuzzers

targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  mapfile -t targets < <(cd tests/fuzz/corpus && ls -d fuzz_* | sort)
fi
work=build/fuzz/work
mkdir -p "$work"
# One target per core at a time (VOCA_FUZZ_JOBS overrides): each is single-threaded.
parallel=${VOCA_FUZZ_JOBS:-$(nproc)}

# Fuzzes one target; its exit status goes to $work/<target>.status.
fuzz_target() {
  local target=$1
  local seeds=tests/fuzz/corpus/$target
  local found=build/fuzz/corpus/$target
  local crashes=build/fuzz/crashes/$target
  mkdir -p "$found" "$crashes"
  # New inputs go to build/fuzz/corpus (the first directory); the seeds are only read.
  # -rss_limit_mb: the video decoder may legitimately allocate a few hundred MB for a large frame.
  local status=0
  TMPDIR=${TMPDIR:-/tmp} "build/asan/bin/$target" "$found" "$seeds" -max_total_time="$seconds" \
    -timeout=10 -rss_limit_mb=2048 -max_len=65536 -print_final_stats=1 -artifact_prefix="$crashes/" \
    >"$work/$target.log" 2>&1 || status=$?
  echo "$status" >"$work/$target.status"
}

for target in "${targets[@]}"; do
  while [ "$(jobs -rp | wc -l)" -ge "$parallel" ]; do wait -n || true; done
  rm -f "$work/$target.status"
  fuzz_target "$target" &
done
wait

failed=()
summary=()
for target in "${targets[@]}"; do
  log=$work/$target.log
  status=$(cat "$work/$target.status" 2>/dev/null || echo "?")
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  if [ "$status" != 0 ]; then
    failed+=("$target")
    echo "FAILED: $target (exit $status); log $log, input in build/fuzz/crashes/$target/"
    grep -m 20 -E 'ERROR|SUMMARY|runtime error|uncaught|Test unit written' "$log" || tail -20 "$log"
  fi
  summary+=("$(printf '%-24s %10s inputs in %s s%s' "$target" "${runs:-?}" "$seconds" "$([ "$status" != 0 ] && echo '  FAILED')")")
done
printf '%s\n' "${summary[@]}"
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzz: ${#failed[@]} target(s) failed: ${failed[*]}"
  exit 1
fi
echo "fuzz: ${#targets[@]} targets, no crash, leak or sanitizer report"
