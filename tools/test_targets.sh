# Sourced by tools/test.sh and tools/asan-aarch64.sh: which tests a CTest filter selects, and which
# of them are build targets, so a tree builds only what it is about to run.

# The names of the tests CTest selects with the given arguments (e.g. --preset asan -L unit).
test_names() {
  ctest -N "$@" | sed -n 's/^ *Test *#[0-9]*: *//p'
}

# The names (after the build directory) that are build targets there. CTest test names are their
# target names, except tests that run a script: those name no target and build with what they run.
build_targets() {
  local build_dir=$1
  shift
  local all
  all=$(ninja -C "$build_dir" -t targets all | sed 's/: .*//')
  for name in "$@"; do
    if grep -qx "$name" <<<"$all"; then echo "$name"; fi
  done
}

# Every default target of a tree except the tests: each top directory's `all` but tests/all.
all_but_tests() {
  ninja -C "$1" -t query all | sed -n '/input: phony/,/outputs:/{/^    /s/^ *//p}' | grep -vx 'tests/all'
}
