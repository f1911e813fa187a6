# SPDX-License-Identifier: Apache-2.0
# Cross-compiling elaslam for arm64 (aarch64) with Debian's multiarch toolchain
# (crossbuild-essential-arm64: aarch64-linux-gnu-gcc/g++). tools/cross_arm64.sh sets
# it up and uses it:
#   cmake -S . -B build-arm64 -G Ninja -DCMAKE_TOOLCHAIN_FILE=cmake/toolchain-aarch64.cmake
#
# Libraries: the Multi-Arch: same ones are installed as :arm64 packages into
# /usr/lib/aarch64-linux-gnu (libsodium-dev:arm64, libsystemd-dev:arm64, ...). LCM and
# yaml-cpp (liblcm-dev, libyaml-cpp-dev) are not Multi-Arch: same in bookworm: their
# :arm64 packages would replace the machine's own, so their .debs are unpacked into
# ELASLAM_CROSS_SYSROOT (a folder of the cross build) and searched there as well.
# Programs (lcm-gen, java) come from the build machine.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(ELASLAM_CROSS_TRIPLET aarch64-linux-gnu)
set(CMAKE_C_COMPILER ${ELASLAM_CROSS_TRIPLET}-gcc)
set(CMAKE_CXX_COMPILER ${ELASLAM_CROSS_TRIPLET}-g++)
set(CMAKE_LIBRARY_ARCHITECTURE ${ELASLAM_CROSS_TRIPLET})

# The unpacked non-multiarch packages (tools/cross_arm64.sh), given on the command line
# or from the environment (try_compile projects see only the environment).
if(NOT ELASLAM_CROSS_SYSROOT AND DEFINED ENV{ELASLAM_CROSS_SYSROOT})
  set(ELASLAM_CROSS_SYSROOT $ENV{ELASLAM_CROSS_SYSROOT})
endif()
set(CMAKE_FIND_ROOT_PATH ${ELASLAM_CROSS_SYSROOT} /)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)  # lcm-gen, java, pkg-config: the build machine's
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
# No RUNPATH into the sysroot in the programs: the packages install them as built
# (lintian: custom-library-search-path). Under qemu-user, tools/cross_arm64.sh gives
# the sysroot's libraries with LD_LIBRARY_PATH.
set(CMAKE_SKIP_BUILD_RPATH ON)
if(ELASLAM_CROSS_SYSROOT)
  # The unpacked libraries' DT_NEEDED of each other, at link time.
  set(CMAKE_EXE_LINKER_FLAGS_INIT "-Wl,-rpath-link,${ELASLAM_CROSS_SYSROOT}/usr/lib/${ELASLAM_CROSS_TRIPLET}")
endif()

# pkg-config (libsodium, libsystemd, cpp-httplib): the arm64 .pc files only.
set(ENV{PKG_CONFIG_LIBDIR} "/usr/lib/${ELASLAM_CROSS_TRIPLET}/pkgconfig:/usr/share/pkgconfig")
set(ENV{PKG_CONFIG_PATH} "")

# Running an arm64 program on the build machine (tests, lcm-gen is not one): qemu-user.
find_program(ELASLAM_QEMU_AARCH64 NAMES qemu-aarch64-static qemu-aarch64)
if(ELASLAM_QEMU_AARCH64)
  set(CMAKE_CROSSCOMPILING_EMULATOR ${ELASLAM_QEMU_AARCH64} -L /usr/${ELASLAM_CROSS_TRIPLET})
endif()
