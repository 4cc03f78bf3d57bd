#!/usr/bin/env bash
# Checks the One Definition Rule across the whole program: builds with link-time optimisation, where
# GCC compares every type with linkage across all translation units (-Wodr, -Wlto-type-mismatch), and
# fails on any report. Two classes of one name with different layouts in two files link silently
# otherwise, and the program then corrupts memory only where the linker's choice of inline copy and
# the inliner's decisions meet: a crash that comes and goes when code moves between files or with the
# target (the estimator split's aarch64-only crash was checked this way, and had no such clash).
#
#   bash tools/check_odr.sh [target...]    e.g. bash tools/check_odr.sh test_backend test_backend_alloc
#
# Default: every target. Build dir build/odr, at -O1 (the check does not depend on the level).
set -euo pipefail
cd "$(dirname "$0")/.."
build=build/odr
log=$build/odr-build.log
lto=(-flto=auto -Wodr -Wlto-type-mismatch)

cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -DNDEBUG" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -DNDEBUG" \
  -DCMAKE_CXX_FLAGS="${lto[*]}" -DCMAKE_EXE_LINKER_FLAGS="${lto[*]}" -DCMAKE_SHARED_LINKER_FLAGS="${lto[*]}" \
  -DCMAKE_MODULE_LINKER_FLAGS="${lto[*]}" >/dev/null

targets=()
[ $# -gt 0 ] && targets=(--target "$@")
# The reports come from the link steps: remove what was linked before so that every link runs again.
mapfile -t link_rules < <(ninja -C "$build" -t rules | grep -E '_LINKER__' || true)
for rule in "${link_rules[@]}"; do ninja -C "$build" -t clean -r "$rule" >/dev/null; done
start=$SECONDS
if ! cmake --build "$build" "${targets[@]}" >"$log" 2>&1; then
  tail -20 "$log" >&2
  echo "check_odr: the build failed; see $log" >&2
  exit 1
fi
reports=$(grep -E -- '\[-W(odr|lto-type-mismatch)\]' "$log" || true)
if [ -n "$reports" ]; then
  echo "check_odr: One Definition Rule violations (full notes in $log):" >&2
  echo "$reports" >&2
  exit 1
fi
echo "check_odr: no One Definition Rule violation in what was linked ($((SECONDS - start)) s)"
