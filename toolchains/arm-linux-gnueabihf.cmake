# Cross-compiles for 32-bit ARM Linux with hardware float (Raspberry Pi OS 32-bit, older boards)
# with Debian 12's arm-linux-gnueabihf toolchain. Prepare the machine with
# `bash tools/cross-setup.sh armhf`, then use the `armhf` presets. Debian's armhf baseline is
# ARMv7-A with VFPv3-D16 and no NEON; for a board that has NEON add
# -mfpu=neon-vfpv4 (or -mcpu=<core>) to CMAKE_CXX_FLAGS.
set(CMAKE_SYSTEM_PROCESSOR armv7l)
set(VOCA_CROSS_TRIPLET arm-linux-gnueabihf)
set(VOCA_CROSS_QEMU arm)
set(VOCA_CROSS_LOADER /lib/ld-linux-armhf.so.3)
include(${CMAKE_CURRENT_LIST_DIR}/debian-multiarch.cmake)
