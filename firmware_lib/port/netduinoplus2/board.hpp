// netduinoplus2: the board support for QEMU's netduinoplus2 machine (Netduino Plus 2: an STM32F405,
// Cortex-M4F, 168 MHz system clock). What is specific to the board: the USART1 driver (usart.cpp:
// interrupt-driven receive into a ring, polled transmit), the vector table and the interrupt numbers
// (board.cpp), the memory map (CMakeLists.txt: origins and sizes for port/common/cortex_m4f.ld).
// Startup, SysTick, semihosting, the stack and the main loop are port/common's (port.hpp). Facts from
// QEMU 7.2's models (hw/arm/netduinoplus2.c, hw/arm/stm32f405_soc.c, include/hw/arm/stm32f405_soc.h,
// hw/char/stm32f2xx_usart.c, include/hw/char/stm32f2xx_usart.h), checked by running
// (docs/firmware.md).
#pragma once

#include <cstdint>

#include "port.hpp"

namespace geojcbb::netduinoplus2 {

using port::reg;

// --- STM32F405 as QEMU models it ---------------------------------------------------------------
/// SYSCLK_FRQ in hw/arm/netduinoplus2.c: the clock of the ARMv7-M "cpuclk", and so of SysTick.
constexpr std::uint32_t kSysClkHz = 168'000'000;
static_assert(port::kSysClkHz == kSysClkHz, "GEOJCBB_SYSCLK_HZ (CMakeLists.txt) is the board's clock");
/// APB2's clock on a 168 MHz STM32F405 (USART1's PCLK2). Only for BRR: QEMU ignores the baud rate.
constexpr std::uint32_t kApb2Hz = 84'000'000;

/// USART1: usart_addr[0] and usart_irq[0] in hw/arm/stm32f405_soc.c; serial_hd(0), that is the first
/// -serial option (QMP label serial0), is connected to it.
constexpr std::uintptr_t kUsart1Base = 0x40011000;
constexpr unsigned kIrqUsart1 = 37;
/// External interrupt lines of the STM32F405 (0..81); QEMU's NVIC has 96 ("num-irq").
constexpr unsigned kExternalIrqs = 82;

/// RCC APB2ENR and its USART1EN bit. QEMU maps RCC as an unimplemented device (writes are ignored);
/// on the part the USART's clock must be on before its registers can be written.
constexpr std::uintptr_t kRccApb2Enr = 0x40023844;
constexpr std::uint32_t kRccApb2EnrUsart1En = 1u << 4;

/// Interrupt handler (vector table entry): USART1 (receive; the only source enabled).
extern "C" void geojcbb_usart1_irq();

}  // namespace geojcbb::netduinoplus2

namespace geojcbb::port {
/// The NVIC line of the UART's receive interrupt (port/common/uart_ring.hpp).
constexpr unsigned kUartRxIrq = netduinoplus2::kIrqUsart1;
}  // namespace geojcbb::port
