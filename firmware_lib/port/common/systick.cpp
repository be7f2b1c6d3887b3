// port/common: SysTick as a free-running instruction counter.
// QEMU has no DWT cycle counter; under `-icount shift=0` every instruction advances the virtual clock
// by 2^0 = 1 ns, and SysTick on the processor clock (CLKSOURCE = 1; QEMU connects the board's SYSCLK
// to the ARMv7-M "cpuclk") counts once per 1e9 / GEOJCBB_SYSCLK_HZ ns of virtual time: once per 40
// instructions at 25 MHz (mps2-an386), once per 125/21 = 5.95 instructions at 168 MHz
// (netduinoplus2). The 24-bit down-counter wraps every 2^24 ticks (671 ms virtual at 25 MHz, 99.9 ms
// at 168 MHz); its interrupt counts the wraps, and a reading combines the wrap count with the current
// value. An integer ratio multiplies in 32 bits (exact modulo 2^32); a fractional one converts the
// 56-bit tick count in 64 bits, floor(ticks * num / den), then keeps the low 32 bits, so differences
// of readings stay exact modulo 2^32 up to the rounding of each reading (< 1 instruction).
#include <cstdint>

#include "port.hpp"

namespace geojcbb::port {
namespace {
constexpr std::uint32_t kReload = 0x00FF'FFFFu;  // period 2^24 ticks
constexpr std::uint32_t kEnable = 1u << 0;
constexpr std::uint32_t kTickInt = 1u << 1;
constexpr std::uint32_t kClkSourceCpu = 1u << 2;
volatile std::uint32_t g_wraps = 0;  // SysTick interrupts taken (the counter reached 0)
}  // namespace

namespace systick {

void start() {
  reg(scs::kSystCsr) = 0;
  reg(scs::kSystRvr) = kReload;
  reg(scs::kSystCvr) = 0;  // any write: the counter reloads on the next tick
  g_wraps = 0;
  reg(scs::kSystCsr) = kClkSourceCpu | kTickInt | kEnable;
}

std::uint32_t instr_now() {
  // Ticks since start = wraps * 2^24 + (2^24 - VAL) mod 2^24: the wrap is counted when VAL reaches
  // 0, and the next tick reloads VAL to 2^24 - 1. With interrupts masked, a wrap whose interrupt is
  // pending (ICSR.PENDSTSET) is counted here and VAL re-read after it.
  std::uint32_t primask;
  __asm volatile("mrs %0, primask\n\tcpsid i" : "=r"(primask)::"memory");
  std::uint32_t wraps = g_wraps;
  std::uint32_t val = reg(scs::kSystCvr);
  if (reg(scs::kIcsr) & scs::kIcsrPendStSet) {
    val = reg(scs::kSystCvr);
    ++wraps;
  }
  __asm volatile("msr primask, %0" ::"r"(primask) : "memory");
  const std::uint32_t in_period = (0x0100'0000u - val) & kReload;
  if constexpr (kInstrPerTickDen == 1) {
    const std::uint32_t ticks = (wraps << 24) + in_period;  // modulo 2^32
    return ticks * kInstrPerTickNum;                        // modulo 2^32
  } else {
    const std::uint64_t ticks = (static_cast<std::uint64_t>(wraps) << 24) + in_period;  // < 2^56
    return static_cast<std::uint32_t>(ticks * kInstrPerTickNum / kInstrPerTickDen);     // < 2^63 before /
  }
}

}  // namespace systick

extern "C" void geojcbb_systick_irq() { g_wraps = g_wraps + 1; }

}  // namespace geojcbb::port
