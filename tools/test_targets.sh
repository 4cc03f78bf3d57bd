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

# Every default target of a tree (what `all` builds) except the named test executables: a tree
# builds what it ships and runs, less the tests another tree runs. Programs that script tests run
# (in tests/, named by no test) stay in.
all_except_tests() {
  local build_dir=$1
  shift
  local skip
  skip=$(printf 'bin/%s\n' "$@")
  local target
  for target in $(phony_inputs "$build_dir" all); do
    if [ "$target" = tests/all ]; then
      phony_inputs "$build_dir" tests/all | grep -vxF -f <(echo "$skip")
    else
      echo "$target"
    fi
  done
}

# What a phony target of a tree (e.g. all, tests/all) stands for, one target a line.
phony_inputs() {
  ninja -C "$1" -t query "$2" | sed -n '/input: phony/,/outputs:/{/^    /s/^ *//p}'
}
