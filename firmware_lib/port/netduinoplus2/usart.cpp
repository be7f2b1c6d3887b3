// netduinoplus2: USART1 of the STM32F405 at 0x40011000, as QEMU 7.2 models it
// (hw/char/stm32f2xx_usart.c): SR +0x00 (ORE bit 3, RXNE bit 5, TC bit 6, TXE bit 7), DR +0x04,
// BRR +0x08, CR1 +0x0C (RE bit 2, TE bit 3, RXNEIE bit 5, UE bit 13). The interrupt line (NVIC IRQ
// 37) is high while SR & CR1 has RXNE (or TXE, TC: their enables stay off).
// The USART holds one received byte (RXNE). Receive is interrupt-driven: the handler moves the byte
// into port/common's ring (uart_ring.hpp), which the main loop drains; reading DR clears RXNE and
// lowers the line, and the model then takes the next byte from the backend. When the ring is full the
// handler masks IRQ 37 at the NVIC and leaves the byte in DR (the model takes no further input while
// RXNE is set); rx_release unmasks and pends it. On hardware further bytes would overrun (ORE,
// counted).
// The model's quirk, the opposite of mps2's: it DROPS every byte that arrives while UE or RE is clear
// (it tells the backend it can receive whenever RXNE is clear). So the reset handler enables the
// USART (UE, TE, RE; no interrupt) in board_early_init, before .data and .bss, and init() only adds
// RXNEIE: a byte that arrived meanwhile waits in DR and raises the interrupt at once. Nothing reads
// DR to "accept input" (that would discard the held byte).
// Transmit polls SR.TXE: QEMU writes each byte synchronously, so TXE is always set there.
#include <cstddef>
#include <cstdint>

#include "board.hpp"
#include "uart_ring.hpp"

namespace geojcbb::port {
namespace {

using netduinoplus2::kApb2Hz;
using netduinoplus2::kIrqUsart1;

constexpr std::uintptr_t kBase = netduinoplus2::kUsart1Base;
constexpr std::uintptr_t kSr = kBase + 0x00;
constexpr std::uintptr_t kDr = kBase + 0x04;
constexpr std::uintptr_t kBrr = kBase + 0x08;
constexpr std::uintptr_t kCr1 = kBase + 0x0C;

constexpr std::uint32_t kSrOre = 1u << 3;
constexpr std::uint32_t kSrRxne = 1u << 5;
constexpr std::uint32_t kSrTc = 1u << 6;
constexpr std::uint32_t kSrTxe = 1u << 7;
constexpr std::uint32_t kCr1Re = 1u << 2;
constexpr std::uint32_t kCr1Te = 1u << 3;
constexpr std::uint32_t kCr1RxneIe = 1u << 5;
constexpr std::uint32_t kCr1Ue = 1u << 13;

constexpr std::uint32_t kEarlyBaud = 115200;

/// BRR for `baud` with 16x oversampling: PCLK2 / baud (mantissa and fraction in one), at least 16.
constexpr std::uint32_t brr(std::uint32_t baud) { return baud == 0 || kApb2Hz / baud < 16 ? 16 : kApb2Hz / baud; }

using ring::g_counters;

}  // namespace

void board_early_init() {
  reg(netduinoplus2::kRccApb2Enr) = reg(netduinoplus2::kRccApb2Enr) | netduinoplus2::kRccApb2EnrUsart1En;
  reg(kBrr) = brr(kEarlyBaud);
  reg(kCr1) = kCr1Ue | kCr1Te | kCr1Re;  // receiving: the first byte waits in DR (no interrupt yet)
}

namespace uart {

void init(std::uint32_t baud) {
  __asm volatile("cpsid i" ::: "memory");  // the handler runs once all of this is done
  reg(kBrr) = brr(baud);
  ring::reset();
  reg(nvic::bank(scs::kNvicIcpr0, kIrqUsart1)) = nvic::bit(kIrqUsart1);
  reg(nvic::bank(scs::kNvicIser0, kIrqUsart1)) = nvic::bit(kIrqUsart1);
  // UE, TE, RE have been on since reset (board_early_init); a byte held in DR raises the interrupt as
  // soon as RXNEIE is set, and it is taken at cpsie.
  reg(kCr1) = kCr1Ue | kCr1Te | kCr1Re | kCr1RxneIe;
  __asm volatile("cpsie i" ::: "memory");
}

void write(const std::uint8_t* data, std::size_t n) {
  ring::write_polled(
      data, n, [] { return (reg(kSr) & kSrTxe) != 0; }, [](std::uint8_t b) { reg(kDr) = b; });
}

void flush() {
  ring::wait_bounded([] { return (reg(kSr) & kSrTc) != 0; });
}

}  // namespace uart

extern "C" void geojcbb_usart1_irq() {  // declared in board.hpp (geojcbb::netduinoplus2)
  const std::uint32_t sr = reg(kSr);
  if ((sr & kSrOre) != 0) {  // hardware only (QEMU does not model it); cleared by this SR read and
    g_counters.rx_overruns = g_counters.rx_overruns + 1;  // the DR read below
  }
  if ((sr & kSrRxne) == 0) {  // no byte held (e.g. the pend of rx_release after a pause was taken)
    g_counters.rx_spurious = g_counters.rx_spurious + 1;
    return;
  }
  if (ring::pause_if_full()) return;  // full: the byte waits in DR, and rx_release runs this again
  // Reading DR clears RXNE and lowers the line; a byte that arrives afterwards raises it again.
  ring::push(static_cast<std::uint8_t>(reg(kDr)));
}

}  // namespace geojcbb::port
