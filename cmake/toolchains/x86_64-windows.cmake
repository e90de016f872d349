# Cross toolchain: Windows x86-64 with mingw-w64 (Debian: gcc-mingw-w64-x86-64).
# The FMI platform (x86_64-windows, FMI 2.0 win64) is derived from CMAKE_SYSTEM_NAME and
# CMAKE_SYSTEM_PROCESSOR by the project's CMakeLists.txt.
set(CMAKE_SYSTEM_NAME Windows)
set(CMAKE_SYSTEM_PROCESSOR x86_64)
# the win32 thread model needs no libwinpthread; the posix one is the fallback
find_program(DFO_MINGW_GCC NAMES x86_64-w64-mingw32-gcc-win32 x86_64-w64-mingw32-gcc REQUIRED)
set(CMAKE_C_COMPILER ${DFO_MINGW_GCC})
find_program(CMAKE_RC_COMPILER NAMES x86_64-w64-mingw32-windres)
set(CMAKE_FIND_ROOT_PATH /usr/x86_64-w64-mingw32)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
# how to run a cross-built program here (tests/platforms, scripts/cross_check.sh)
find_program(DFO_WINE NAMES wine wine64 PATHS /usr/lib/wine)
if(DFO_WINE)
  set(CMAKE_CROSSCOMPILING_EMULATOR ${DFO_WINE})
endif()
