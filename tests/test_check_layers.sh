#!/usr/bin/env bash
# tools/check_layers.sh on made-up trees: a clean one passes; each forbidden include (quoted or
# angled, indented) is reported with its file and line and fails the check; an allowed downward
# include is not reported.
set -euo pipefail
check=${1:?usage: $0 <path to check_layers.sh>}
tree=$(mktemp -d)
trap 'rm -rf "$tree"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

mkdir -p "$tree"/{voca/frontend,formats/calib,drivers/decode,pipeline/vo,platform/realtime,tools/voca,api/python}
printf '#include "voca/core/image.h"\n#include <vector>\n' >"$tree/voca/frontend/ok.cpp"
printf '#include "voca/calib/calibration.h"\n#include <nlohmann/json.hpp>\n' >"$tree/formats/calib/ok.cpp"
printf '#include "voca/core/image.h"\n#include "formats/calib/ok.h"\n#include "platform/realtime/clock.h"\n' \
  >"$tree/drivers/decode/ok.cpp"
printf '#include "drivers/decode/ok.h"\n#include "voca/frontend/ok.h"\n' >"$tree/pipeline/vo/ok.cpp"
printf '#include "pipeline/vo/ok.h"\n' >"$tree/tools/voca/ok.cpp"
printf '#include "voca_rt/odometry.h"\n#include <pybind11/pybind11.h>\n' >"$tree/api/python/ok.cpp"
bash "$check" "$tree" >/dev/null || fail "a clean tree was rejected"

expect_violation() {  # <file> <include line> <rule text>
  local file=$1 line=$2 rule=$3 out rc=0
  printf '// header\n%s\n' "$line" >"$tree/$file"
  out=$(bash "$check" "$tree" 2>&1) || rc=$?
  [[ $rc -eq 1 ]] || fail "$file with '$line': exit $rc, expected 1"
  grep -qF "$file:2: $rule" <<<"$out" || fail "$file with '$line' not reported as '$rule': $out"
  rm "$tree/$file"
}
expect_violation voca/frontend/bad.cpp '#include "drivers/decode/video_decoder.h"' "voca/ must not include"
expect_violation voca/frontend/bad.h '  #  include <pipeline/runtime/stage.h>' "voca/ must not include"
expect_violation voca/frontend/bad.cpp '#include "tools/voca/command.h"' "voca/ must not include"
expect_violation voca/frontend/bad.cpp '#include "platform/realtime/clock.h"' "voca/ must not include"
expect_violation voca/frontend/bad.cpp '#include "formats/calib/calibration_io.h"' "voca/ must not include"
expect_violation formats/calib/bad.cpp '#include "drivers/decode/video_decoder.h"' "formats/ must not include"
expect_violation formats/calib/bad.h '#include <pipeline/vo/vo_runner.h>' "formats/ must not include"
expect_violation formats/calib/bad.cpp '#include "tools/voca/command.h"' "formats/ must not include"
expect_violation drivers/decode/bad.cpp '#include "pipeline/vo/vo_runner.h"' "drivers/ must not include"
expect_violation drivers/decode/bad.cpp '#include "tools/voca/command.h"' "drivers/ must not include"
expect_violation pipeline/vo/bad.cpp '#include "tools/voca/pipeline_cli.h"' "pipeline/ must not include"
expect_violation platform/realtime/bad.cpp '#include "drivers/decode/video_decoder.h"' "platform/ must not include"
expect_violation api/python/bad.cpp '#include "api/src/api_internal.h"' "api/python/ must not include"
expect_violation api/python/bad.cpp '#include "pipeline/vo/vo_session.h"' "api/python/ must not include"
bash "$check" "$tree" >/dev/null || fail "the tree is not clean again after the bad files were removed"

rc=0
bash "$check" "$tree/nonexistent" >/dev/null 2>&1 || rc=$?
[[ $rc -eq 2 ]] || fail "a missing root gave exit $rc, expected 2"
echo "check_layers.sh: clean tree passes, 14 kinds of cross-layer include fail"
