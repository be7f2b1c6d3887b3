// port/common: the UART receive ring, shared by the boards' UART drivers. Single producer (the
// board's RX interrupt: head), single consumer (thread mode: tail); free-running indices, head - tail
// is the fill level. The thread side (uart::rx_peek, rx_release, wait_for_rx, counters) is
// port/common's (uart_ring.cpp); the handler side is these inline helpers. When the ring is full the
// handler masks its IRQ at the NVIC and leaves the byte in the UART (back-pressure, not loss: QEMU's
// models take no further input while a byte is held); rx_release() unmasks the IRQ and pends it once.
// A board defines geojcbb::port::kUartRxIrq (its NVIC line) in its board.hpp.
#pragma once

#include <cstddef>
#include <cstdint>

#include "board.hpp"
#include "port.hpp"

namespace geojcbb::port::ring {

static_assert((uart::kRxRingSize & (uart::kRxRingSize - 1)) == 0, "ring size: a power of two");
constexpr std::uint32_t kMask = uart::kRxRingSize - 1;

extern std::uint8_t g_ring[uart::kRxRingSize];
extern volatile std::uint32_t g_head;
extern volatile std::uint32_t g_tail;
extern volatile bool g_paused;  // the RX IRQ is masked because the ring was full
extern volatile uart::Counters g_counters;

inline void barrier() { __asm volatile("" ::: "memory"); }

/// Thread mode, interrupts masked (uart::init): empties the ring.
inline void reset() {
  g_head = g_tail = 0;
  g_paused = false;
}

/// Handler side: when the ring is full, pauses reception (masks the RX IRQ at the NVIC, counts a
/// stall) and returns true; the byte stays in the UART until rx_release() runs the handler again.
inline bool pause_if_full() {
  if (g_head - g_tail != uart::kRxRingSize) return false;
  g_paused = true;
  g_counters.rx_stalls = g_counters.rx_stalls + 1;
  reg(nvic::bank(scs::kNvicIcer0, kUartRxIrq)) = nvic::bit(kUartRxIrq);
  __asm volatile("dsb\n\tisb" ::: "memory");
  return true;
}

/// Handler side: appends one byte (the ring is not full: pause_if_full() said so).
inline void push(std::uint8_t byte) {
  const std::uint32_t head = g_head;
  g_ring[head & kMask] = byte;
  barrier();
  g_head = head + 1;
  g_counters.rx_bytes = g_counters.rx_bytes + 1;
}

/// Thread side, polled transmit for the boards' uart::write: for each byte waits, at most
/// kTxSpinLimit polls, until `ready()`, then `put(byte)`; a byte whose transmitter stays busy is
/// dropped and counted (tx_dropped). Bound: n * kTxSpinLimit polls.
template <class Ready, class Put>
inline void write_polled(const std::uint8_t* data, std::size_t n, Ready ready, Put put) {
  for (std::size_t i = 0; i < n; ++i) {  // <= n
    std::uint32_t spins = 0;
    while (!ready() && spins < uart::kTxSpinLimit) ++spins;  // <= kTxSpinLimit
    if (spins == uart::kTxSpinLimit) {
      g_counters.tx_dropped = g_counters.tx_dropped + 1;
      continue;
    }
    put(data[i]);
    g_counters.tx_bytes = g_counters.tx_bytes + 1;
  }
}

/// Thread side: waits until `done()`, at most kTxSpinLimit polls (uart::flush).
template <class Done>
inline void wait_bounded(Done done) {
  for (std::uint32_t spins = 0; !done() && spins < uart::kTxSpinLimit; ++spins) {
  }  // <= kTxSpinLimit
}

}  // namespace geojcbb::port::ring
