// mps2_an386: the board support for QEMU's mps2-an386 machine (ARM MPS2 with the AN386 FPGA image,
// Cortex-M4F, 25 MHz system clock). What is specific to the board: the UART0 driver (uart.cpp:
// CMSDK APB UART0, interrupt-driven receive into a ring, polled transmit), the vector table and the
// interrupt numbers (board.cpp), the memory map (CMakeLists.txt: origins and sizes for
// port/common/cortex_m4f.ld). Startup, SysTick, semihosting, the stack and the main loop are
// port/common's (port.hpp). Layouts follow QEMU's models (hw/arm/mps2.c, hw/char/cmsdk-apb-uart.c,
// hw/timer/armv7m_systick.c) and the ARMv7-M architecture manual; docs/firmware.md has the memory
// map and the design.
#pragma once

#include <cstdint>

#include "port.hpp"

namespace geojcbb::mps2 {

using port::reg;

// --- AN386 external interrupts (QEMU hw/arm/mps2.c: UART0 RX on 0, TX on 1) -----------------
constexpr unsigned kIrqUart0Rx = 0;
constexpr unsigned kIrqUart0Tx = 1;     ///< not used: transmit polls
constexpr unsigned kExternalIrqs = 32;  ///< the AN386 NVIC has 32 external lines

/// The system clock that drives SysTick (CLKSOURCE = processor clock) and the UART's baud divider.
constexpr std::uint32_t kSysClkHz = 25'000'000;
static_assert(port::kSysClkHz == kSysClkHz, "GEOJCBB_SYSCLK_HZ (CMakeLists.txt) is the board's clock");

/// Interrupt handlers (vector table entries).
extern "C" void geojcbb_uart0_rx_irq();

}  // namespace geojcbb::mps2

namespace geojcbb::port {
/// The NVIC line of the UART's receive interrupt (port/common/uart_ring.hpp).
constexpr unsigned kUartRxIrq = mps2::kIrqUart0Rx;
}  // namespace geojcbb::port
