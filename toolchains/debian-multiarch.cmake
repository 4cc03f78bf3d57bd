# Shared part of the Debian cross toolchain files: the caller sets CMAKE_SYSTEM_PROCESSOR,
# VOCA_CROSS_TRIPLET (GNU triplet, also the multiarch directory name), VOCA_CROSS_QEMU (qemu-user
# name of the CPU) and VOCA_CROSS_LOADER (the target's dynamic loader as libc6:<arch> installs it).
# Libraries come from the multiarch directories that tools/cross-setup.sh fills (/usr/lib/<triplet>,
# /usr/include/<triplet>); header-only and arch:all packages are shared with the host. Test
# executables run under qemu-user, so `ctest` works on the build machine.
set(CMAKE_SYSTEM_NAME Linux)

set(CMAKE_C_COMPILER ${VOCA_CROSS_TRIPLET}-gcc)
set(CMAKE_CXX_COMPILER ${VOCA_CROSS_TRIPLET}-g++)
# CMake derives this from the compiler too; stating it keeps find_library/find_package away from
# the host's /usr/lib/x86_64-linux-gnu even if the detection changes.
set(CMAKE_LIBRARY_ARCHITECTURE ${VOCA_CROSS_TRIPLET})

# Packages that Debian does not ship Multi-Arch: same (yaml-cpp) are unpacked by cross-setup.sh into
# a private overlay; it is searched before the system root.
if(DEFINED ENV{VOCA_CROSS_OVERLAY})
  set(VOCA_CROSS_OVERLAY "$ENV{VOCA_CROSS_OVERLAY}/${VOCA_CROSS_TRIPLET}")
else()
  set(VOCA_CROSS_OVERLAY "/opt/voca-cross/${VOCA_CROSS_TRIPLET}")
endif()
set(CMAKE_FIND_ROOT_PATH ${VOCA_CROSS_OVERLAY} /)
# The overlay's libraries are links to the multiarch directory, where the board has them too:
# treating it as implicit keeps a build-machine path out of the executables' RUNPATH.
list(APPEND CMAKE_PLATFORM_IMPLICIT_LINK_DIRECTORIES ${VOCA_CROSS_OVERLAY}/usr/lib/${VOCA_CROSS_TRIPLET})
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)  # build tools (pkg-config, ...) run on the host
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# pkg-config must see only the target's .pc files (and arch-independent ones), never the host's.
# The toolchain file is read on every configure, so this holds for re-configures during a build.
set(ENV{PKG_CONFIG_LIBDIR}
    "${VOCA_CROSS_OVERLAY}/usr/lib/${VOCA_CROSS_TRIPLET}/pkgconfig:/usr/lib/${VOCA_CROSS_TRIPLET}/pkgconfig:/usr/share/pkgconfig")
set(ENV{PKG_CONFIG_PATH} "")
unset(ENV{PKG_CONFIG_SYSROOT_DIR})

# Run test executables (add_test with a target as COMMAND) through qemu-user. With the target's
# libc installed multiarch (libc6:<arch>, pulled in by the -dev packages), qemu needs no -L: the
# loader and every library resolve in /lib/<triplet> and /usr/lib/<triplet> as on a Debian board.
# `-L /usr/<triplet>` would pair the cross toolchain's ld.so with the multiarch libc, two different
# glibc builds: that runs, but lazy binding then never sticks and every libc call through the PLT
# repeats the symbol lookup (libx264 encodes ran >100x slower than they should). So -L is only the
# fallback when the multiarch libc is absent.
find_program(VOCA_QEMU NAMES qemu-${VOCA_CROSS_QEMU}-static qemu-${VOCA_CROSS_QEMU} NO_CMAKE_FIND_ROOT_PATH)
if(NOT VOCA_QEMU)
  message(WARNING "qemu-${VOCA_CROSS_QEMU}-static not found (bash tools/cross-setup.sh installs it): "
                  "the build works, but ctest cannot run the ${CMAKE_SYSTEM_PROCESSOR} test executables here")
elseif(EXISTS ${VOCA_CROSS_LOADER})
  set(CMAKE_CROSSCOMPILING_EMULATOR ${VOCA_QEMU})
else()
  set(CMAKE_CROSSCOMPILING_EMULATOR ${VOCA_QEMU} -L /usr/${VOCA_CROSS_TRIPLET})
endif()
