# Cross-compiles for 32-bit ARM Linux with hardware float (Raspberry Pi OS 32-bit, older boards)
# with Debian 12's arm-linux-gnueabihf toolchain. Prepare the machine with
# `bash tools/cross-setup.sh armhf`, then use the `armhf` presets. Debian's armhf baseline is
# ARMv7-A with VFPv3-D16 and no NEON; for a board that has NEON configure with
# -DCMAKE_CXX_FLAGS="-Wno-psabi -mfpu=neon-vfpv4" (or -mcpu=<core>): giving CMAKE_CXX_FLAGS replaces
# the default below, so repeat -Wno-psabi.
set(CMAKE_SYSTEM_PROCESSOR armv7l)
set(VOCA_CROSS_TRIPLET arm-linux-gnueabihf)
set(VOCA_CROSS_QEMU arm)
set(VOCA_CROSS_LOADER /lib/ld-linux-armhf.so.3)
# GCC on 32-bit ARM notes every function taking a std::span, std::pair or iterator by value that its
# argument passing changed in GCC 7.1/10.1 (-Wpsabi). That matters only when linking objects built by
# those older compilers; everything in Debian 12 armhf is GCC 12, so the notes are noise.
set(CMAKE_C_FLAGS_INIT -Wno-psabi)
set(CMAKE_CXX_FLAGS_INIT -Wno-psabi)
include(${CMAKE_CURRENT_LIST_DIR}/debian-multiarch.cmake)
