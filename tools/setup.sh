#!/usr/bin/env bash
# Installs every Debian 12 package VOCA-RT needs to build, test and run. Idempotent: when all
# packages are present it only checks and returns. Run as root, or as a user with sudo.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev                                  # geometry and solvers
  libavcodec-dev libavformat-dev libavutil-dev libswscale-dev libx264-dev  # H.264 encode/decode with MVs
  libva-dev libdrm-dev                           # VAAPI hardware decode
  libcamera-dev                                  # libcamera capture
  libconcurrentqueue-dev libreaderwriterqueue-dev  # lock-free queues between pipeline stages
  doctest-dev                                    # unit tests
  nlohmann-json3-dev                             # JSON: Basalt calibration, configs, reports
  libyaml-cpp-dev                                # YAML: Kalibr camchains, EuRoC sensor.yaml
  libcli11-dev                                   # command-line parsing
  libfmt-dev                                     # formatting (GCC 12 has no std::format)
  libpng-dev                                     # PNG datasets
  cyclonedds-dev cyclonedds-tools                # ROS 2 odometry over DDS (--ros2); idlc generates the message types
  libwebsocketpp-dev libasio-dev                 # live view (--view): Foxglove WebSocket server, header-only
  clang-14 libclang-rt-14-dev                    # libFuzzer + sanitizers for tests/fuzz (tools/fuzz.sh)
  python3-matplotlib                             # plots of evaluation suites (tools/plot_suite.py)
  python3-websockets python3-jsonschema python3-pil chromium  # live view tests: protocol client, schemas, the page in headless chromium
  python3                                        # the MCAP reader test (tests/mcap_reader.py: standard library only)
  pybind11-dev python3-pybind11 python3-dev      # the Python module voca (api/python)
  python3-numpy python3-pytest                 # ... its arrays, and its tests (pytest, PNG frames)
  dpkg-dev file                                  # Debian packages with cpack: dpkg-shlibdeps, ELF detection
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages present"
  exit 0
fi

sudo=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "setup: need root (or sudo) to install: ${missing[*]}" >&2; exit 1; }
  sudo="sudo"
fi
echo "setup: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
echo "setup: done"
