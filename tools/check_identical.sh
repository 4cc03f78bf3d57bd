#!/usr/bin/env bash
# Shows that two builds of the voca tool estimate the same trajectories, byte for byte: for a
# refactoring that must not change behaviour (issue 13). Runs the same inputs through both binaries
# and compares the sha256 of every trajectory file; prints the hashes and exits non-zero on any
# difference.
#
#   tools/check_identical.sh <voca-A> <voca-B> [--euroc <EuRoC folder>] [--kitti <sequence folder>]
#
# Always: a synthetic aggressive sequence (generated and encoded once with binary A) run with
# --mode none and --mode mv_parallel_of. Optional: an EuRoC folder (calibration from its
# camN/sensor.yaml) and a KITTI odometry sequence folder (calib.txt, --config kitti), each run on its
# raw images and encoded on the fly at 500k; with the KITTI ground truth beside it
# (../../poses/<sequence>.txt), also the `voca eval --json` report of the 500k trajectory.
# Every input with motion vectors also runs in other thread layouts (the frontend on one thread and
# with its helper, --frontend-threads 1 / 2, and every stage on one thread, --threads 1), compared
# across the binaries like any run, and each binary's layouts with one another: where a stage runs
# must not change what it computes.
set -euo pipefail

usage() {
  echo "usage: $0 <voca-A> <voca-B> [--euroc <EuRoC folder>] [--kitti <sequence folder>]" >&2
  exit 2
}
[[ $# -ge 2 ]] || usage
voca_a=$(realpath "$1")
voca_b=$(realpath "$2")
shift 2
euroc=""
kitti=""
while [[ $# -gt 0 ]]; do
  case "$1" in
    --euroc) euroc=$(realpath "${2:?--euroc needs a folder}"); shift 2 ;;
    --kitti) kitti=$(realpath "${2:?--kitti needs a folder}"); shift 2 ;;
    *) usage ;;
  esac
done
for binary in "$voca_a" "$voca_b"; do
  [[ -x "$binary" ]] || { echo "$0: $binary is not an executable" >&2; exit 2; }
done

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"

echo "inputs: synthetic aggressive sequence (6 s), encoded at 500k" >&2
"$voca_a" synth --out s --motion aggressive --seconds 6 >/dev/null
"$voca_a" encode s --out s500 --bitrate 500k >/dev/null

# name and arguments of each run; the trajectory goes to <label>/<name>.txt
runs=("synth_none|run s500 --mode none"
      "synth_mv_parallel_of|run s500 --mode mv_parallel_of")
[[ -n "$euroc" ]] && runs+=("euroc_raw|run $euroc" "euroc_500k|run $euroc --encode 500k")
[[ -n "$kitti" ]] && runs+=("kitti_raw|run $kitti --config kitti" "kitti_500k|run $kitti --config kitti --encode 500k")
# The thread layouts: each run named here again as <name>_<layout>.
layouts=("frontend1|--frontend-threads 1" "frontend2|--frontend-threads 2" "threads1|--threads 1")
layout_runs=(synth_mv_parallel_of)
[[ -n "$euroc" ]] && layout_runs+=(euroc_500k)
[[ -n "$kitti" ]] && layout_runs+=(kitti_500k)
for name in "${layout_runs[@]}"; do
  for run in "${runs[@]}"; do
    [[ ${run%%|*} == "$name" ]] || continue
    for layout in "${layouts[@]}"; do runs+=("${name}_${layout%%|*}|${run#*|} ${layout#*|}"); done
  done
done

status=0
for run in "${runs[@]}"; do
  name=${run%%|*}
  args=${run#*|}
  for label in a b; do
    binary=$voca_a
    [[ $label == b ]] && binary=$voca_b
    mkdir -p "$label"
    # shellcheck disable=SC2086  # the arguments are split on purpose
    "$binary" $args --out "$label/$name.txt" >"$label/$name.log" 2>&1 ||
      { echo "$name: voca ($label) failed:" >&2; tail -5 "$label/$name.log" >&2; status=1; continue 2; }
  done
  hash_a=$(sha256sum "a/$name.txt" | cut -d' ' -f1)
  hash_b=$(sha256sum "b/$name.txt" | cut -d' ' -f1)
  lines=$(wc -l <"a/$name.txt")
  if [[ "$hash_a" == "$hash_b" ]]; then
    echo "identical  $name  $hash_a  ($lines lines)"
  else
    echo "DIFFERENT  $name  A $hash_a  B $hash_b"
    status=1
  fi
done

# Each binary's layouts against its default layout.
for name in "${layout_runs[@]}"; do
  same=1
  for label in a b; do
    [[ -f $label/$name.txt ]] || { same=0; continue; }  # its failure is reported above
    hash_default=$(sha256sum "$label/$name.txt" | cut -d' ' -f1)
    for layout in "${layouts[@]}"; do
      file="$label/${name}_${layout%%|*}.txt"
      [[ -f $file ]] || { same=0; continue; }
      hash_layout=$(sha256sum "$file" | cut -d' ' -f1)
      if [[ "$hash_layout" != "$hash_default" ]]; then
        echo "DIFFERENT  ${name}_${layout%%|*} ($label) $hash_layout, its default layout $hash_default"
        same=0
        status=1
      fi
    done
  done
  if [[ $same == 1 ]]; then echo "identical  $name in every layout, in A and in B"; fi
done

# The evaluation report reads the calibration, both trajectories and the times file and writes JSON.
ground_truth=${kitti:+$(dirname "$(dirname "$kitti")")/poses/$(basename "$kitti").txt}
if [[ -n "$kitti" && -f "$ground_truth" && -f a/kitti_500k.txt ]]; then
  for label in a b; do
    binary=$voca_a
    [[ $label == b ]] && binary=$voca_b
    "$binary" eval --gt "$ground_truth" --gt-times "$kitti/times.txt" --est a/kitti_500k.txt --calib "$kitti" \
      --json "$label/kitti_eval.json" >"$label/kitti_eval.log" 2>&1 ||
      { echo "kitti_eval: voca ($label) failed:" >&2; tail -5 "$label/kitti_eval.log" >&2; status=1; }
  done
  if [[ -f a/kitti_eval.json && -f b/kitti_eval.json ]]; then
    hash_a=$(sha256sum a/kitti_eval.json | cut -d' ' -f1)
    hash_b=$(sha256sum b/kitti_eval.json | cut -d' ' -f1)
    if [[ "$hash_a" == "$hash_b" ]]; then
      echo "identical  kitti_eval_json  $hash_a"
    else
      echo "DIFFERENT  kitti_eval_json  A $hash_a  B $hash_b"
      status=1
    fi
  fi
fi
exit $status
