# port/common: the CMake side of the board-independent firmware code (included by each board's
# CMakeLists.txt). Cross build only. docs/firmware.md.
set(GEOJCBB_PORT_COMMON_DIR ${CMAKE_CURRENT_LIST_DIR})
set(GEOJCBB_PORT_LD ${CMAKE_CURRENT_LIST_DIR}/cortex_m4f.ld)

# geojcbb_port_board(NAME SYSCLK_HZ hz SOURCES src...)
# The board library: the board's sources (UART driver, vector table) and port/common's startup,
# SysTick and receive ring, compiled with the board's clock (GEOJCBB_SYSCLK_HZ).
function(geojcbb_port_board name)
  cmake_parse_arguments(B "" "SYSCLK_HZ" "SOURCES" ${ARGN})
  add_library(${name} STATIC ${B_SOURCES} ${GEOJCBB_PORT_COMMON_DIR}/startup.cpp ${GEOJCBB_PORT_COMMON_DIR}/systick.cpp
    ${GEOJCBB_PORT_COMMON_DIR}/uart_ring.cpp)
  target_include_directories(${name} PUBLIC ${CMAKE_CURRENT_SOURCE_DIR} ${GEOJCBB_PORT_COMMON_DIR})
  target_compile_definitions(${name} PUBLIC GEOJCBB_SYSCLK_HZ=${B_SYSCLK_HZ})
  target_link_libraries(${name} PRIVATE geojcbb_warnings)
  target_compile_options(${name} PRIVATE -fstack-usage -fcallgraph-info=su)
endfunction()

# geojcbb_port_link(TARGET FLASH_ORIGIN addr FLASH bytes RAM_ORIGIN addr RAM bytes STACK bytes)
# Links TARGET with port/common's script (no crt0, no picolibc.ld, and so no heap symbols; picolibc's
# libc and libgcc still link: memcpy, memset, soft helpers) in a FLASH/RAM map of the given origins
# and sizes (the stack is part of RAM, at its top). Static data over RAM - STACK is a link error.
function(geojcbb_port_link target)
  cmake_parse_arguments(L "" "FLASH_ORIGIN;FLASH;RAM_ORIGIN;RAM;STACK" "" ${ARGN})
  target_link_options(${target} PRIVATE -nostartfiles -T${GEOJCBB_PORT_LD}
    -Wl,--defsym=__flash_origin=${L_FLASH_ORIGIN} -Wl,--defsym=__flash_size=${L_FLASH}
    -Wl,--defsym=__ram_origin=${L_RAM_ORIGIN} -Wl,--defsym=__ram_size=${L_RAM} -Wl,--defsym=__stack_size=${L_STACK})
  set_target_properties(${target} PROPERTIES SUFFIX .elf LINK_DEPENDS ${GEOJCBB_PORT_LD})
endfunction()

# geojcbb_port_firmware(NAME BOARD lib BOUNDS type FLASH_ORIGIN addr FLASH bytes RAM_ORIGIN addr RAM bytes
#                       STACK bytes [OPTIMIZE flags...] [DEFINES definitions...])
# builds NAME.elf: port/common's main loop with the node at `type` (a geojcbb::Bounds) on board `lib`.
function(geojcbb_port_firmware name)
  cmake_parse_arguments(F "" "BOARD;BOUNDS;FLASH_ORIGIN;FLASH;RAM_ORIGIN;RAM;STACK" "OPTIMIZE;DEFINES" ${ARGN})
  add_executable(${name} ${GEOJCBB_PORT_COMMON_DIR}/main.cpp)
  if(F_DEFINES)  # the image's own choices (e.g. GEOJCBB_WITHOUT_HYPOTHESES, core/capacity.hpp)
    target_compile_definitions(${name} PRIVATE ${F_DEFINES})
  endif()
  if(F_OPTIMIZE)  # after the build type's flags, so it wins (e.g. -O2 where -O3's unrolling overflows flash)
    target_compile_options(${name} PRIVATE ${F_OPTIMIZE})
  endif()
  target_link_libraries(${name} PRIVATE ${F_BOARD} geojcbb::firmware)
  target_compile_definitions(${name} PRIVATE "GEOJCBB_BOARD_BOUNDS=${F_BOUNDS}")
  # Frame sizes and the call graph for the stack tests.
  target_link_libraries(${name} PRIVATE geojcbb_warnings)
  target_compile_options(${name} PRIVATE -fstack-usage -fcallgraph-info=su)
  geojcbb_port_link(${name} FLASH_ORIGIN ${F_FLASH_ORIGIN} FLASH ${F_FLASH} RAM_ORIGIN ${F_RAM_ORIGIN} RAM ${F_RAM}
                    STACK ${F_STACK})
  target_link_options(${name} PRIVATE -Wl,-Map=${CMAKE_CURRENT_BINARY_DIR}/${name}.map -Wl,--print-memory-usage)
endfunction()

find_program(GEOJCBB_QEMU_ARM qemu-system-arm)
if(NOT GEOJCBB_QEMU_ARM)
  set(GEOJCBB_QEMU_ARM qemu-system-arm)  # the QEMU tests fail and say so
endif()
set(GEOJCBB_QEMU_HARNESS ${PROJECT_SOURCE_DIR}/build/host-release/host_tools/geojcbb_qemu CACHE FILEPATH
    "geojcbb_qemu, the host side of the end-to-end QEMU tests")
set(GEOJCBB_UART_CHECK ${PROJECT_SOURCE_DIR}/build/host-release/host_tools/geojcbb_uart_check CACHE FILEPATH
    "geojcbb_uart_check (host-release), the host side of the QEMU smoke tests")

# geojcbb_port_firmware_tests(PREFIX name ELF target BOARD lib MACHINE qemu-machine ISR regex STACK bytes
#                             SESSION hexfile [LEAD_DELIMITERS n])
# The checks of one firmware ELF (CTest, cortex-m4f preset): PREFIX.no_heap (no allocator, exception,
# RTTI or stdio symbols), .size (text/data/bss), .stack_frames (every frame <= 512 B, all static),
# .stack_call_chain (the deepest chain from main - the loop, Node::on_bytes, the indirect calls
# through the board's Output and clock - plus an interrupt on top, <= 2 KiB) and .qemu_smoke (a QEMU
# run of SESSION on the board's UART, after LEAD_DELIMITERS empty frames: it must exit with status 0
# and answer every frame).
function(geojcbb_port_firmware_tests)
  cmake_parse_arguments(T "" "PREFIX;ELF;BOARD;MACHINE;ISR;STACK;SESSION;LEAD_DELIMITERS" "" ${ARGN})
  if(NOT T_LEAD_DELIMITERS)
    set(T_LEAD_DELIMITERS 0)
  endif()
  set(check ${PROJECT_SOURCE_DIR}/toolchains/check_firmware.cmake)
  set(board_dir ${CMAKE_CURRENT_BINARY_DIR}/CMakeFiles/${T_BOARD}.dir)
  set(obj_dir ${CMAKE_CURRENT_BINARY_DIR}/CMakeFiles/${T_ELF}.dir)
  set(indirect "^(_ZN12_GLOBAL__N_1[0-9]+(write_bytes|shutdown)E.*|_ZN7geojcbb4port7systick9instr_nowEv)$")
  add_test(NAME ${T_PREFIX}.no_heap
    COMMAND ${CMAKE_COMMAND} -DNM=${GEOJCBB_NM} -DFILE=$<TARGET_FILE:${T_ELF}> -DMODE=symbols -P ${check})
  add_test(NAME ${T_PREFIX}.size
    COMMAND ${CMAKE_COMMAND} -DSIZE=${GEOJCBB_SIZE} -DFILE=$<TARGET_FILE:${T_ELF}> -DMODE=size -P ${check})
  add_test(NAME ${T_PREFIX}.stack_frames
    COMMAND ${CMAKE_COMMAND} "-DSU_DIR=${obj_dir}|${board_dir}" -DMAX_FRAME=512 -DMODE=stack -P ${check})
  add_test(NAME ${T_PREFIX}.stack_call_chain
    COMMAND ${CMAKE_COMMAND} "-DCI_DIR=${obj_dir}|${board_dir}" "-DROOT=^main$" -DMAX_CHAIN=2048
            "-DINDIRECT=${indirect}" "-DISR=${T_ISR}" -DEXCEPTION_FRAME=104 -DMODE=callgraph -P ${check})
  add_test(NAME ${T_PREFIX}.qemu_smoke
    COMMAND ${CMAKE_COMMAND} -DQEMU=${GEOJCBB_QEMU_ARM} -DMACHINE=${T_MACHINE} -DELF=$<TARGET_FILE:${T_ELF}>
            -DINPUT=${T_SESSION} -DWORK_DIR=${CMAKE_CURRENT_BINARY_DIR}/smoke_${T_ELF}
            -DTIMEOUT=120 -DMAX_STACK=${T_STACK} -DLEAD_DELIMITERS=${T_LEAD_DELIMITERS}
            -DUART_CHECK=${GEOJCBB_UART_CHECK} -DMODE=qemu -P ${check})
endfunction()
