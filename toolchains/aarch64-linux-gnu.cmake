# Cross-compiles for 64-bit ARM Linux (Jetson, Raspberry Pi 3/4/5 with a 64-bit OS, Rockchip, most
# headset SoCs) with Debian 12's aarch64-linux-gnu toolchain. Prepare the machine with
# `bash tools/cross-setup.sh aarch64`, then use the `aarch64` presets.
# AdvSIMD (NEON) is part of ARMv8-A, so the baseline -march already has it; pass -mcpu=<core> in
# CMAKE_CXX_FLAGS to tune for one board.
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(VOCA_CROSS_TRIPLET aarch64-linux-gnu)
set(VOCA_CROSS_QEMU aarch64)
set(VOCA_CROSS_LOADER /lib/ld-linux-aarch64.so.1)
include(${CMAKE_CURRENT_LIST_DIR}/debian-multiarch.cmake)
