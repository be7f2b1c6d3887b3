# Cross-compilation for ARM Cortex-M4F (hard float, FPv4-SP) with Debian's gcc-arm-none-eabi,
# picolibc-arm-none-eabi and libstdc++-arm-none-eabi-picolibc.
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)

set(CMAKE_C_COMPILER arm-none-eabi-gcc)
set(CMAKE_CXX_COMPILER arm-none-eabi-g++)
set(CMAKE_AR arm-none-eabi-ar)
set(CMAKE_RANLIB arm-none-eabi-ranlib)
set(GEOJCBB_NM arm-none-eabi-nm CACHE STRING "nm for the target")
set(GEOJCBB_SIZE arm-none-eabi-size CACHE STRING "size for the target")
# Try-compiles build a static library: there is no startup code to link an executable against yet.
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

set(GEOJCBB_CPU_FLAGS "-mcpu=cortex-m4 -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16")
set(CMAKE_C_FLAGS_INIT "${GEOJCBB_CPU_FLAGS} --specs=picolibc.specs -ffunction-sections -fdata-sections")
set(CMAKE_CXX_FLAGS_INIT "${GEOJCBB_CPU_FLAGS} --specs=picolibcpp.specs -ffunction-sections -fdata-sections -fno-exceptions -fno-rtti -fno-threadsafe-statics -fno-use-cxa-atexit -DEIGEN_NO_MALLOC")
set(CMAKE_EXE_LINKER_FLAGS_INIT "-Wl,--gc-sections")

# Libraries and headers come from the target sysroot; Eigen (header-only, architecture-independent)
# is found through the host's package registry.
set(CMAKE_FIND_ROOT_PATH /usr/lib/picolibc/arm-none-eabi)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE BOTH)
