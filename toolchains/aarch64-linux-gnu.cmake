# Flight target: 64-bit ARM Linux (the class of the lander's flight computer), with Debian's
# cross compiler. Tests run under user-mode QEMU because binfmt is not registered on these hosts.
#
# Target libraries (tools/run installs them): Aravis, GLib, libv4l, stb and zlib are Debian's arm64
# packages co-installed as multiarch (/usr/lib/aarch64-linux-gnu); LCM's arm64 packages are not
# multiarch and are unpacked into SWF_AARCH64_SYSROOT instead.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)

if(NOT SWF_AARCH64_SYSROOT)
  if(DEFINED ENV{SWF_AARCH64_SYSROOT})
    set(SWF_AARCH64_SYSROOT $ENV{SWF_AARCH64_SYSROOT})
  else()
    set(SWF_AARCH64_SYSROOT /opt/swf-aarch64-sysroot)
  endif()
endif()
set(SWF_AARCH64_SYSROOT ${SWF_AARCH64_SYSROOT} CACHE PATH
    "LCM's arm64 packages unpacked (tools/run install_aarch64_sysroot)")

# "/" for the multiarch libraries (the compiler's library architecture picks their aarch64
# directories), the cross C library's own directory, and LCM's sysroot.
set(CMAKE_FIND_ROOT_PATH /usr/aarch64-linux-gnu / ${SWF_AARCH64_SYSROOT})
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
# pkg-config answers for the target only: LCM's file (its prefix rewritten to the sysroot) and the
# multiarch ones, never the host's.
set(ENV{PKG_CONFIG_LIBDIR}
    "${SWF_AARCH64_SYSROOT}/usr/lib/aarch64-linux-gnu/pkgconfig:/usr/lib/aarch64-linux-gnu/pkgconfig:/usr/share/pkgconfig")
set(ENV{PKG_CONFIG_PATH} "")

# The loader and C library at run time are Debian's arm64 glibc (libc6:arm64, multiarch, the one a
# Debian flight computer runs; its libm decides the transcendental functions' bits), found at its
# real paths; liblcm through the run path CMake links into every program.
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-aarch64 -L /)

# Eigen's NEON multiply-add (pmadd) is fused when __ARM_FEATURE_FMA is defined, which it always is
# on ARMv8; the host's SSE2 build multiplies and adds, rounding twice. With the macro undefined,
# Eigen multiplies and adds on aarch64 too (kept apart by -ffp-contract=off): the same bits as the
# host (docs/aarch64.md, tests/cross_isa).
set(CMAKE_CXX_FLAGS_INIT "-U__ARM_FEATURE_FMA")
