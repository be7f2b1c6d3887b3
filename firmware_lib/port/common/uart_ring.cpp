// port/common: the thread side of the UART receive ring (uart_ring.hpp), shared by the boards.
#include "uart_ring.hpp"

#include <cstddef>
#include <cstdint>

namespace geojcbb::port {

namespace ring {
std::uint8_t g_ring[uart::kRxRingSize];
volatile std::uint32_t g_head = 0;
volatile std::uint32_t g_tail = 0;
volatile bool g_paused = false;
volatile uart::Counters g_counters;
}  // namespace ring

namespace uart {

std::size_t rx_peek(const std::uint8_t** data) {
  const std::uint32_t tail = ring::g_tail;
  const std::uint32_t used = ring::g_head - tail;
  ring::barrier();  // the bytes below head were written before head
  const std::uint32_t start = tail & ring::kMask;
  const std::uint32_t contiguous = kRxRingSize - start;
  *data = &ring::g_ring[start];
  return used < contiguous ? used : contiguous;
}

void rx_release(std::size_t n) {
  ring::barrier();  // the caller is done with the bytes before they are handed back
  ring::g_tail = ring::g_tail + static_cast<std::uint32_t>(n);
  if (ring::g_paused) {  // the handler masked itself: it cannot run until unmasked here
    ring::g_paused = false;
    reg(nvic::bank(scs::kNvicIser0, kUartRxIrq)) = nvic::bit(kUartRxIrq);
    reg(nvic::bank(scs::kNvicIspr0, kUartRxIrq)) = nvic::bit(kUartRxIrq);  // run it once even if its
                                                                           // request was cleared
  }
}

void wait_for_rx() {
  __asm volatile("cpsid i" ::: "memory");
  if (ring::g_head == ring::g_tail) __asm volatile("dsb\n\twfi" ::: "memory");  // a pending interrupt wakes it
  __asm volatile("cpsie i\n\tisb" ::: "memory");                                // the interrupt is taken here
}

Counters counters() {
  Counters c;
  c.rx_bytes = ring::g_counters.rx_bytes;
  c.rx_stalls = ring::g_counters.rx_stalls;
  c.rx_overruns = ring::g_counters.rx_overruns;
  c.rx_spurious = ring::g_counters.rx_spurious;
  c.tx_bytes = ring::g_counters.tx_bytes;
  c.tx_dropped = ring::g_counters.tx_dropped;
  return c;
}

}  // namespace uart
}  // namespace geojcbb::port
