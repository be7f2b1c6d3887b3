// port/common: the vector table of a Cortex-M4F board, built at compile time. 16 system entries and
// the board's external lines: initial SP (__stack_top), Reset, NMI, HardFault, SysTick (vector 15)
// and the UART's receive interrupt; every other entry exits with exit_status::kUnexpectedIrq.
// MemManage, BusFault and UsageFault are not enabled, so they escalate to HardFault.
// A board defines its table, in FLASH at the image's first address (.vectors), as the extern "C"
// object geojcbb_vector_table (the linker script requires that name):
//   __attribute__((section(".vectors"), used)) constexpr VectorTable<kExternalIrqs> geojcbb_vector_table =
//       geojcbb::port::make_vector_table<kExternalIrqs>(kIrqUartRx, uart_rx_handler);
#pragma once

#include <cstddef>
#include <cstdint>

#include "port.hpp"

extern "C" {
extern std::uint32_t __stack_top[];  // linker script
void Reset_Handler();
void geojcbb_nmi();
void geojcbb_hard_fault();
void geojcbb_unexpected_irq();
}

namespace geojcbb::port {

using Vector = void (*)();
constexpr std::size_t kSystemVectors = 16;

/// The table as an array of entries: entry 0 is the initial stack pointer, the others handlers.
template <std::size_t kExternalIrqs>
struct VectorTable {
  const void* initial_sp;
  Vector handler[kSystemVectors + kExternalIrqs - 1];
};

template <std::size_t kExternalIrqs>
constexpr VectorTable<kExternalIrqs> make_vector_table(unsigned uart_rx_irq, Vector uart_rx_handler) {
  constexpr std::size_t kVectors = kSystemVectors + kExternalIrqs;
  VectorTable<kExternalIrqs> t{__stack_top, {}};
  for (std::size_t i = 0; i < kVectors - 1; ++i) t.handler[i] = geojcbb_unexpected_irq;  // kVectors
  t.handler[1 - 1] = Reset_Handler;
  t.handler[2 - 1] = geojcbb_nmi;
  t.handler[3 - 1] = geojcbb_hard_fault;  // MemManage, BusFault, UsageFault are not enabled: they
                                          // escalate to HardFault
  t.handler[15 - 1] = geojcbb_systick_irq;
  t.handler[kSystemVectors + uart_rx_irq - 1] = uart_rx_handler;
  return t;
}

}  // namespace geojcbb::port
