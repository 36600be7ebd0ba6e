# Bare-metal Cortex-M7 with its double-precision FPU (fpv5-d16, hard float), Debian's
# gcc-arm-none-eabi and libstdc++-arm-none-eabi-newlib. Used by tests/baremetal (docs/baremetal.md)
# to build the online kernels of algorithms/ as a freestanding library and run their tests on an
# emulated core (qemu-system-arm -M mps2-an500) through semihosting.
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR cortex-m7)
set(CMAKE_C_COMPILER arm-none-eabi-gcc)
set(CMAKE_CXX_COMPILER arm-none-eabi-g++)
set(CMAKE_ASM_COMPILER arm-none-eabi-gcc)
# CMake's compiler checks cannot link a program before the project's start-up code exists.
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

set(HARMOLOC_M7_CPU_FLAGS "-mcpu=cortex-m7 -mthumb -mfpu=fpv5-d16 -mfloat-abi=hard")
set(CMAKE_C_FLAGS_INIT "${HARMOLOC_M7_CPU_FLAGS}")
set(CMAKE_CXX_FLAGS_INIT "${HARMOLOC_M7_CPU_FLAGS}")
set(CMAKE_ASM_FLAGS_INIT "${HARMOLOC_M7_CPU_FLAGS}")
# rdimon: newlib's system calls over semihosting (console output, exit status, arguments).
set(CMAKE_EXE_LINKER_FLAGS_INIT "--specs=rdimon.specs")

set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# ctest and add_test run target programs on the emulated board.
get_filename_component(HARMOLOC_M7_QEMU
  "${CMAKE_CURRENT_LIST_DIR}/../tests/baremetal/qemu-mps2-an500.sh" ABSOLUTE)
set(CMAKE_CROSSCOMPILING_EMULATOR "${HARMOLOC_M7_QEMU}")
