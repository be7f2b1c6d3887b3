// mps2_an386: the board support for QEMU's mps2-an386 machine (ARM MPS2 with the AN386 FPGA image,
// Cortex-M4F, 25 MHz system clock). Register addresses and the small drivers the firmware needs:
//   uart      CMSDK APB UART0: interrupt-driven receive into a ring, polled transmit
//   systick   SysTick as a 32-bit instruction counter (under QEMU's -icount shift=0)
//   stack     the main stack: painted at boot, high-water mark on demand
//   semihost  SYS_EXIT_EXTENDED, so QEMU exits with the firmware's status
// Layouts follow QEMU's models (hw/arm/mps2.c, hw/char/cmsdk-apb-uart.c, hw/timer/armv7m_systick.c)
// and the ARMv7-M architecture manual; docs/firmware.md has the memory map and the design.
#pragma once

#include <cstddef>
#include <cstdint>

namespace geojcbb::mps2 {

/// A memory-mapped 32-bit register.
inline volatile std::uint32_t& reg(std::uintptr_t address) {
  return *reinterpret_cast<volatile std::uint32_t*>(address);
}

// --- Cortex-M4 system control space ---------------------------------------------------------
namespace scs {
constexpr std::uintptr_t kSystCsr = 0xE000E010;    ///< SysTick control and status
constexpr std::uintptr_t kSystRvr = 0xE000E014;    ///< SysTick reload value
constexpr std::uintptr_t kSystCvr = 0xE000E018;    ///< SysTick current value
constexpr std::uintptr_t kNvicIser0 = 0xE000E100;  ///< NVIC set-enable, IRQ 0..31
constexpr std::uintptr_t kNvicIcer0 = 0xE000E180;  ///< NVIC clear-enable, IRQ 0..31
constexpr std::uintptr_t kNvicIspr0 = 0xE000E200;  ///< NVIC set-pending, IRQ 0..31
constexpr std::uintptr_t kNvicIcpr0 = 0xE000E280;  ///< NVIC clear-pending, IRQ 0..31
constexpr std::uintptr_t kIcsr = 0xE000ED04;       ///< interrupt control and state
// CPACR (0xE000ED88) is written by the reset handler's assembly only.
constexpr std::uintptr_t kMpuType = 0xE000ED90;
constexpr std::uintptr_t kMpuCtrl = 0xE000ED94;
constexpr std::uintptr_t kMpuRnr = 0xE000ED98;
constexpr std::uintptr_t kMpuRbar = 0xE000ED9C;
constexpr std::uintptr_t kMpuRasr = 0xE000EDA0;
constexpr std::uint32_t kIcsrPendStSet = 1u << 26;  ///< SysTick exception pending
}  // namespace scs

// --- AN386 external interrupts (QEMU hw/arm/mps2.c: UART0 RX on 0, TX on 1) -----------------
constexpr unsigned kIrqUart0Rx = 0;
constexpr unsigned kIrqUart0Tx = 1;     ///< not used: transmit polls
constexpr unsigned kExternalIrqs = 32;  ///< the AN386 NVIC has 32 external lines

/// The system clock that drives SysTick (CLKSOURCE = processor clock) and the UART's baud divider.
constexpr std::uint32_t kSysClkHz = 25'000'000;

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
/// Instructions per SysTick tick under `-icount shift=0`: one instruction per nanosecond of virtual
/// time, one tick per 1e9 / 25 MHz = 40 ns (SysTick on the processor clock, docs/firmware.md).
constexpr std::uint32_t kInstructionsPerTick = 1'000'000'000u / kSysClkHz;
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

namespace uart {
struct Counters {
  std::uint32_t rx_bytes = 0;     ///< bytes moved from DATA into the ring
  std::uint32_t rx_stalls = 0;    ///< times the ring was full and reception paused (no byte lost)
  std::uint32_t rx_overruns = 0;  ///< bytes the UART itself lost (RXOVERRUN: real hardware only)
  std::uint32_t rx_spurious = 0;  ///< receive interrupts that found no byte (see init())
  std::uint32_t tx_bytes = 0;
  std::uint32_t tx_dropped = 0;  ///< bytes given up after kTxSpinLimit polls of a full transmitter
};
/// Receive ring capacity (a power of two).
constexpr std::size_t kRxRingSize = 512;
/// Polls of STATE.TXFULL per byte before the byte is dropped.
constexpr std::uint32_t kTxSpinLimit = 1u << 24;  // ~4 instructions a poll: ~67 ms of virtual time

/// UART0 8N1 at `baud`; TX enabled, RX enabled with its interrupt (NVIC IRQ 0).
void init(std::uint32_t baud);
/// The longest contiguous run of received bytes not yet released: *data points into the ring.
/// Thread mode only. @return its length (0: nothing received).
std::size_t rx_peek(const std::uint8_t** data);
/// Frees the first n bytes returned by rx_peek and resumes a paused reception.
void rx_release(std::size_t n);
/// Sleeps (WFI) until a byte is in the ring; returns at once if one already is. No wake-up is lost:
/// interrupts are masked while the ring is checked, and WFI wakes on a pending interrupt.
void wait_for_rx();
/// Writes n bytes, polling STATE.TXFULL (the frames are small, at most ~1 KB per message).
/// Bound: n * kTxSpinLimit polls.
void write(const std::uint8_t* data, std::size_t n);
/// Waits until the last written byte has left the transmit register. Bound: kTxSpinLimit polls.
void flush();
Counters counters();
}  // namespace uart

/// Interrupt handlers (vector table entries).
extern "C" void geojcbb_uart0_rx_irq();
extern "C" void geojcbb_systick_irq();

}  // namespace geojcbb::mps2
