// netduinoplus2: the vector table (16 system and 82 external entries, USART1 on external IRQ 37,
// vector 53). The early-init hook is usart.cpp's.
#include "board.hpp"

#include "vectors.hpp"

// The table (port/common/vectors.hpp), built at compile time (constexpr: no constructor runs for it),
// in .vectors, the first output section of FLASH. It has an external name, which the linker script
// requires (EXTERN), so the board library's member that holds it is always linked; `used` keeps the
// compiler from dropping it, and the linker KEEPs it.
using BoardVectorTable = geojcbb::port::VectorTable<geojcbb::netduinoplus2::kExternalIrqs>;
extern "C" const BoardVectorTable geojcbb_vector_table;
__attribute__((section(".vectors"), used)) constexpr BoardVectorTable geojcbb_vector_table =
    geojcbb::port::make_vector_table<geojcbb::netduinoplus2::kExternalIrqs>(geojcbb::netduinoplus2::kIrqUsart1,
                                                                            geojcbb::netduinoplus2::geojcbb_usart1_irq);
