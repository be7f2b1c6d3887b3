// mps2_an386: the vector table (16 system and 32 external entries: the AN386 NVIC has 32 lines; UART0
// RX is external IRQ 0, vector 16) and the early-init hook (nothing to do: the CMSDK UART holds input
// until it is enabled, see uart.cpp).
#include "board.hpp"

#include "vectors.hpp"

namespace geojcbb::port {
void board_early_init() {}
}  // namespace geojcbb::port

// The table (port/common/vectors.hpp), built at compile time (constexpr: no constructor runs for it),
// in .vectors, the first output section of FLASH. It has an external name, which the linker script
// requires (EXTERN), so the board library's member that holds it is always linked; `used` keeps the
// compiler from dropping it, and the linker KEEPs it.
using BoardVectorTable = geojcbb::port::VectorTable<geojcbb::mps2::kExternalIrqs>;
extern "C" const BoardVectorTable geojcbb_vector_table;
__attribute__((section(".vectors"), used)) constexpr BoardVectorTable geojcbb_vector_table =
    geojcbb::port::make_vector_table<geojcbb::mps2::kExternalIrqs>(geojcbb::mps2::kIrqUart0Rx,
                                                                   geojcbb::mps2::geojcbb_uart0_rx_irq);
