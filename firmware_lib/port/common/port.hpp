// port/common: what every Cortex-M4F board port shares (mps2_an386, netduinoplus2). The register
// access, the system control space, exit statuses, and the interfaces of the board-independent
// pieces (implemented here in port/common):
//   semihost  SYS_EXIT_EXTENDED, so QEMU exits with the firmware's status
//   systick   SysTick as a 32-bit instruction counter (under QEMU's -icount shift=0)
//   stack     the main stack: painted at boot, MPU guard, high-water mark on demand
// and of the board-specific ones (implemented by each board):
//   uart      interrupt-driven receive into a ring, polled transmit
//   board_early_init, the vector table (port/common/vectors.hpp)
// Compile definition: GEOJCBB_SYSCLK_HZ, the clock SysTick counts (CLKSOURCE = processor clock).
// docs/firmware.md has the memory maps and the design.
#pragma once

#include <cstddef>
#include <cstdint>

#ifndef GEOJCBB_SYSCLK_HZ
#error "GEOJCBB_SYSCLK_HZ: the board's processor clock in Hz"
#endif

namespace geojcbb::port {

/// A memory-mapped 32-bit register.
inline volatile std::uint32_t& reg(std::uintptr_t address) {
  return *reinterpret_cast<volatile std::uint32_t*>(address);
}

// --- Cortex-M4 system control space ---------------------------------------------------------
namespace scs {
constexpr std::uintptr_t kSystCsr = 0xE000E010;    ///< SysTick control and status
constexpr std::uintptr_t kSystRvr = 0xE000E014;    ///< SysTick reload value
constexpr std::uintptr_t kSystCvr = 0xE000E018;    ///< SysTick current value
constexpr std::uintptr_t kNvicIser0 = 0xE000E100;  ///< NVIC set-enable, IRQ 0..31 (+4 per 32 IRQs)
constexpr std::uintptr_t kNvicIcer0 = 0xE000E180;  ///< NVIC clear-enable
constexpr std::uintptr_t kNvicIspr0 = 0xE000E200;  ///< NVIC set-pending
constexpr std::uintptr_t kNvicIcpr0 = 0xE000E280;  ///< NVIC clear-pending
constexpr std::uintptr_t kIcsr = 0xE000ED04;       ///< interrupt control and state
// CPACR (0xE000ED88) is written by the reset handler's assembly only.
constexpr std::uintptr_t kMpuType = 0xE000ED90;
constexpr std::uintptr_t kMpuCtrl = 0xE000ED94;
constexpr std::uintptr_t kMpuRnr = 0xE000ED98;
constexpr std::uintptr_t kMpuRbar = 0xE000ED9C;
constexpr std::uintptr_t kMpuRasr = 0xE000EDA0;
constexpr std::uint32_t kIcsrPendStSet = 1u << 26;  ///< SysTick exception pending
}  // namespace scs

namespace nvic {
/// The NVIC register of bank `base` (ISER0, ICER0, ISPR0, ICPR0) that holds external IRQ `irq`.
constexpr std::uintptr_t bank(std::uintptr_t base, unsigned irq) { return base + 4u * (irq / 32u); }
/// The bit of IRQ `irq` in its register.
constexpr std::uint32_t bit(unsigned irq) { return 1u << (irq % 32u); }
}  // namespace nvic

/// The processor clock: SysTick counts it (CLKSOURCE = 1).
constexpr std::uint32_t kSysClkHz = GEOJCBB_SYSCLK_HZ;

// --- Exit statuses (semihosting SYS_EXIT_EXTENDED; QEMU exits with them) ---------------------
namespace exit_status {
constexpr std::uint32_t kHardFault = 0xE1;      ///< HardFault (and escalated MemManage/Bus/Usage)
constexpr std::uint32_t kNmi = 0xE2;            ///< NMI
constexpr std::uint32_t kUnexpectedIrq = 0xE3;  ///< an interrupt without a handler
constexpr std::uint32_t kMainReturned = 0xE4;   ///< main() returned (it never should)
}  // namespace exit_status

namespace semihost {
/// SYS_EXIT_EXTENDED (ADP_Stopped_ApplicationExit, status): under
/// `-semihosting-config enable=on,target=native` QEMU exits with `status` (low 8 bits on a POSIX host).
/// Without semihosting enabled the BKPT is a HardFault, which ends here again: the core locks up.
[[noreturn]] void exit(std::uint32_t status);
}  // namespace semihost

namespace systick {
/// Greatest common divisor (compile time; Euclid's loop, at most ~45 steps for 32-bit operands).
constexpr std::uint32_t gcd(std::uint32_t a, std::uint32_t b) {
  while (b != 0) {
    const std::uint32_t r = a % b;
    a = b;
    b = r;
  }
  return a;
}
/// Instructions per SysTick tick under `-icount shift=0` (one instruction per nanosecond of virtual
/// time): 1e9 / kSysClkHz, as the reduced fraction kInstrPerTickNum / kInstrPerTickDen (40 / 1 at
/// 25 MHz, 125 / 21 at 168 MHz).
constexpr std::uint32_t kInstrPerTickNum = 1'000'000'000u / gcd(1'000'000'000u, kSysClkHz);
constexpr std::uint32_t kInstrPerTickDen = kSysClkHz / gcd(1'000'000'000u, kSysClkHz);
/// A reading's resolution, rounded up (40 at 25 MHz, 6 at 168 MHz).
constexpr std::uint32_t kInstructionsPerTick = (kInstrPerTickNum + kInstrPerTickDen - 1) / kInstrPerTickDen;
/// Starts SysTick: processor clock, reload 2^24 - 1, wrap interrupt (counts the wraps).
void start();
/// Free-running instruction count, modulo 2^32 (a stage's count is a difference of two readings;
/// resolution kInstructionsPerTick). Thread mode or any context at SysTick's priority or below.
std::uint32_t instr_now();
}  // namespace systick

namespace stack {
/// The word the reset handler paints the stack with.
constexpr std::uint32_t kPaint = 0x57AC57ACu;
/// Bytes of the MPU guard at the bottom of the stack (no access: an overflow is a MemManage fault,
/// escalated to HardFault, which exits with exit_status::kHardFault).
constexpr std::uint32_t kGuardBytes = 32;
/// Programs the MPU guard region. Called once from the reset handler.
void install_guard();
/// Deepest use of the main stack so far, bytes below its top (the lowest overwritten painted word).
/// Bound: one read per unused stack word (stack size / 4).
std::uint32_t high_water();
/// Usable stack bytes (the stack region minus the guard).
std::uint32_t capacity();
}  // namespace stack

/// Board hook, called by the reset handler before .data and .bss are set up (so it may touch neither):
/// what must happen as early as possible (netduinoplus2: enable the USART so that no byte is dropped).
void board_early_init();

// --- The board's UART (each board implements these) ---------------------------------------------
namespace uart {
struct Counters {
  std::uint32_t rx_bytes = 0;     ///< bytes moved from the data register into the ring
  std::uint32_t rx_stalls = 0;    ///< times the ring was full and reception paused (no byte lost)
  std::uint32_t rx_overruns = 0;  ///< bytes the UART itself lost (overrun flag: real hardware only)
  std::uint32_t rx_spurious = 0;  ///< receive interrupts that found no byte
  std::uint32_t tx_bytes = 0;
  std::uint32_t tx_dropped = 0;  ///< bytes given up after kTxSpinLimit polls of a busy transmitter
};
/// Receive ring capacity (a power of two).
constexpr std::size_t kRxRingSize = 512;
/// Polls of the transmitter per byte before the byte is dropped.
constexpr std::uint32_t kTxSpinLimit = 1u << 24;  // ~4 instructions a poll: ~67 ms of virtual time

/// 8N1 at `baud`; TX enabled, RX enabled with its interrupt.
void init(std::uint32_t baud);
/// The longest contiguous run of received bytes not yet released: *data points into the ring.
/// Thread mode only. @return its length (0: nothing received).
std::size_t rx_peek(const std::uint8_t** data);
/// Frees the first n bytes returned by rx_peek and resumes a paused reception.
void rx_release(std::size_t n);
/// Sleeps (WFI) until a byte is in the ring; returns at once if one already is. No wake-up is lost:
/// interrupts are masked while the ring is checked, and WFI wakes on a pending interrupt.
void wait_for_rx();
/// Writes n bytes, polling the transmitter (the frames are small, at most ~1 KB per message).
/// Bound: n * kTxSpinLimit polls.
void write(const std::uint8_t* data, std::size_t n);
/// Waits until the last written byte has left the transmit register. Bound: kTxSpinLimit polls.
void flush();
Counters counters();
}  // namespace uart

/// The SysTick handler (vector 15), in port/common/systick.cpp.
extern "C" void geojcbb_systick_irq();

}  // namespace geojcbb::port
