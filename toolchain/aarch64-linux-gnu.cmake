# Cross toolchain: Debian's aarch64-linux-gnu GCC against an arm64 sysroot made of
# Debian 12's own arm64 packages (toolchain/install-cross-deps.sh builds it; default
# build/sysroot-arm64, or -DENDOTOWER_SYSROOT=DIR, or the ENDOTOWER_SYSROOT variable).
# Tests run through qemu-user (CMAKE_CROSSCOMPILING_EMULATOR); see toolchain/cross-test.sh.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)

if(NOT ENDOTOWER_SYSROOT)
  if(DEFINED ENV{ENDOTOWER_SYSROOT})
    set(ENDOTOWER_SYSROOT $ENV{ENDOTOWER_SYSROOT})
  else()
    get_filename_component(ENDOTOWER_SYSROOT "${CMAKE_CURRENT_LIST_DIR}/../build/sysroot-arm64" ABSOLUTE)
  endif()
endif()
if(NOT EXISTS "${ENDOTOWER_SYSROOT}/usr/lib/aarch64-linux-gnu")
  message(FATAL_ERROR "no arm64 sysroot at ${ENDOTOWER_SYSROOT}: run toolchain/install-cross-deps.sh first")
endif()
# Passed on to try_compile projects, which load this file again.
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES ENDOTOWER_SYSROOT)

set(CMAKE_SYSROOT "${ENDOTOWER_SYSROOT}")
set(CMAKE_FIND_ROOT_PATH "${ENDOTOWER_SYSROOT}")
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
# The sysroot's libraries find their own dependencies at link time.
set(CMAKE_EXE_LINKER_FLAGS_INIT "-Wl,-rpath-link,${ENDOTOWER_SYSROOT}/usr/lib/aarch64-linux-gnu -Wl,-rpath-link,${ENDOTOWER_SYSROOT}/lib/aarch64-linux-gnu")

set(ENV{PKG_CONFIG_SYSROOT_DIR} "${ENDOTOWER_SYSROOT}")
set(ENV{PKG_CONFIG_LIBDIR} "${ENDOTOWER_SYSROOT}/usr/lib/aarch64-linux-gnu/pkgconfig:${ENDOTOWER_SYSROOT}/usr/share/pkgconfig")

# Unit tests run on the host under qemu-user, with the sysroot as the library prefix.
find_program(ENDOTOWER_QEMU_AARCH64 NAMES qemu-aarch64-static qemu-aarch64)
if(ENDOTOWER_QEMU_AARCH64)
  set(CMAKE_CROSSCOMPILING_EMULATOR "${ENDOTOWER_QEMU_AARCH64};-L;${ENDOTOWER_SYSROOT}")
endif()
