#!/usr/bin/env bash
# Runs the library example and `voca run` on the same video folder (micro EuRoC V1_01, encoded by
# `voca encode`) and requires the example's rows to equal the trajectory file's, byte for byte.
#
#   test_example_odometry.sh <voca_example_odometry> <voca> <shared data folder>
#
# Exit 77 (CTest: skipped) when the shared data is absent, a failure instead with CI=true.
set -euo pipefail
example=$1 voca=$2 data=${VOCA_SHARED_DATA:-$3}
dataset="$data/euroc_v101_micro/mav0"
if [ ! -d "$dataset" ]; then
  echo "test_example_odometry: $dataset: no such folder (../shared/data is needed)" >&2
  [ "${CI:-}" = true ] && exit 1
  exit 77
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

"$voca" encode "$dataset" --out "$work/video" >/dev/null
"$voca" run "$work/video" --out "$work/cli.tum" >/dev/null
"$example" "$work/video" "$work/video/calib.json" >"$work/example.tum"

grep -v '^#' "$work/cli.tum" >"$work/cli_rows.tum"
rows=$(wc -l <"$work/cli_rows.tum")
if [ "$rows" -lt 50 ]; then
  echo "test_example_odometry: voca run wrote only $rows poses" >&2
  exit 1
fi
if ! cmp "$work/cli_rows.tum" "$work/example.tum"; then
  { diff "$work/cli_rows.tum" "$work/example.tum" || true; } | head -20 >&2
  echo "test_example_odometry: the example's rows differ from voca run --out" >&2
  exit 1
fi
echo "test_example_odometry: $rows rows identical to voca run --out"
