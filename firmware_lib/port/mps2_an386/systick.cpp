// mps2_an386: SysTick as a free-running instruction counter.
// QEMU has no DWT cycle counter; under `-icount shift=0` every instruction advances the virtual clock
// by 2^0 = 1 ns, and SysTick on the processor clock (CLKSOURCE = 1; QEMU connects the board's 25 MHz
// SYSCLK to the ARMv7-M "cpuclk") counts once per 40 ns of virtual time, that is once per 40
// instructions. The 24-bit down-counter wraps every 2^24 ticks (671 ms virtual); its interrupt
// counts the wraps, and a reading combines the wrap count with the current value.
#include <cstdint>

#include "board.hpp"

namespace geojcbb::mps2 {
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
  const std::uint32_t ticks = (wraps << 24) + ((0x0100'0000u - val) & kReload);  // modulo 2^32
  return ticks * kInstructionsPerTick;                                           // modulo 2^32
}

}  // namespace systick

extern "C" void geojcbb_systick_irq() { g_wraps = g_wraps + 1; }

}  // namespace geojcbb::mps2
