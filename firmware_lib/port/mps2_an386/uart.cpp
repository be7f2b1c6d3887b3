// mps2_an386: CMSDK APB UART0 at 0x40004000.
//   DATA +0x0, STATE +0x4 (TXFULL, RXFULL, TXOVERRUN, RXOVERRUN), CTRL +0x8 (TX_EN, RX_EN, TX_INTEN,
//   RX_INTEN, ...), INTSTATUS/INTCLEAR +0xC (write 1 to clear), BAUDDIV +0x10 (>= 16).
// The UART holds one received byte. Receive is interrupt-driven (NVIC IRQ 0): the handler moves the
// byte into port/common's ring (uart_ring.hpp), which the main loop drains. When the ring is full the handler masks IRQ
// 0 at the NVIC and leaves the byte in DATA; the line stays high, so the interrupt is taken again as soon as the main
// loop frees space and unmasks it. Under QEMU nothing is lost (the model accepts no further input while RXFULL is set);
// on hardware further bytes would overrun the UART, which is counted. Transmit polls STATE.TXFULL: a message is at most
// ~1 KB, and QEMU's model sends a byte at once unless the host side is not reading.
#include <cstddef>
#include <cstdint>

#include "board.hpp"
#include "uart_ring.hpp"

namespace geojcbb::port {
namespace {

using mps2::kIrqUart0Rx;

constexpr std::uintptr_t kBase = 0x40004000;
constexpr std::uintptr_t kData = kBase + 0x0;
constexpr std::uintptr_t kState = kBase + 0x4;
constexpr std::uintptr_t kCtrl = kBase + 0x8;
constexpr std::uintptr_t kIntClear = kBase + 0xC;
constexpr std::uintptr_t kBaudDiv = kBase + 0x10;

constexpr std::uint32_t kStateTxFull = 1u << 0;
constexpr std::uint32_t kStateRxFull = 1u << 1;
constexpr std::uint32_t kStateTxOverrun = 1u << 2;
constexpr std::uint32_t kStateRxOverrun = 1u << 3;
constexpr std::uint32_t kCtrlTxEn = 1u << 0;
constexpr std::uint32_t kCtrlRxEn = 1u << 1;
constexpr std::uint32_t kCtrlRxIntEn = 1u << 3;
constexpr std::uint32_t kIntRx = 1u << 1;

using ring::g_counters;

}  // namespace

namespace uart {

void init(std::uint32_t baud) {
  __asm volatile("cpsid i" ::: "memory");  // the handler runs once all of this is done
  reg(kCtrl) = 0;
  reg(kBaudDiv) = baud == 0 || kSysClkHz / baud < 16 ? 16 : kSysClkHz / baud;  // the divider's minimum is 16
  reg(kIntClear) = 0xF;
  reg(kState) = kStateRxOverrun | kStateTxOverrun;  // write 1 to clear
  ring::reset();
  reg(scs::kNvicIcpr0) = 1u << kIrqUart0Rx;  // the UART is off: nothing can pend it again yet
  reg(scs::kNvicIser0) = 1u << kIrqUart0Rx;
  // QEMU quirk: enabling RX does not tell the character backend that the UART can take input; a
  // read of DATA does, and without it no byte ever arrives (on hardware the read discards a stale
  // byte). The read comes right after the enable and nothing is cleared after it: the first byte
  // can arrive as soon as DATA has been read, and its interrupt request must survive. (A byte that
  // arrived in the one instruction between enable and read would be consumed by the read; the
  // handler then finds no byte and counts rx_spurious. A host that starts with a delimiter loses
  // nothing even then.)
  reg(kCtrl) = kCtrlTxEn | kCtrlRxEn | kCtrlRxIntEn;
  const std::uint32_t stale = reg(kData);
  static_cast<void>(stale);
  __asm volatile("cpsie i" ::: "memory");
}

void write(const std::uint8_t* data, std::size_t n) {
  ring::write_polled(
      data, n, [] { return (reg(kState) & kStateTxFull) == 0; }, [](std::uint8_t b) { reg(kData) = b; });
}

void flush() {
  ring::wait_bounded([] { return (reg(kState) & kStateTxFull) == 0; });
}

}  // namespace uart

extern "C" void geojcbb_uart0_rx_irq() {  // declared in board.hpp (geojcbb::mps2)
  std::uint32_t state = reg(kState);
  if ((state & kStateRxOverrun) != 0) {
    g_counters.rx_overruns = g_counters.rx_overruns + 1;
    reg(kState) = kStateRxOverrun;  // write 1 to clear
  }
  if ((state & kStateRxFull) == 0) {  // no byte held: clear the request, then look once more, as a
    reg(kIntClear) = kIntRx;          // byte that arrived meanwhile may have had its request cleared
    state = reg(kState);
    if ((state & kStateRxFull) == 0) {
      g_counters.rx_spurious = g_counters.rx_spurious + 1;
      return;
    }
  }
  if (ring::pause_if_full()) return;  // full: the byte waits in DATA, and rx_release runs this again
  // Clear the request before reading DATA: the model takes no byte while RXFULL is set, and a byte
  // that arrives once DATA has been read raises the request again.
  reg(kIntClear) = kIntRx;
  ring::push(static_cast<std::uint8_t>(reg(kData)));
}

}  // namespace geojcbb::port
