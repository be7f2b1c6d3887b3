// port/common: startup, shared by the boards. The reset handler, the fault handlers, semihosting
// exit and the stack (paint, MPU guard, high-water mark); each board supplies its vector table
// (vectors.hpp) and board_early_init(). Reset sequence (docs/firmware.md):
//   1. (asm, before any compiled code) enable the FPU: CPACR CP10/CP11 full access, DSB, ISB;
//   2. (asm) paint the whole stack region with stack::kPaint (nothing is on the stack yet);
//   3. board_early_init() (touches neither .data nor .bss);
//   4. copy .data from FLASH, zero .bss, install the MPU stack guard;
//   5. run the static constructors (.preinit_array, .init_array);
//   6. main(); if it returns, exit through semihosting with exit_status::kMainReturned.
// Faults (HardFault, NMI, any interrupt without a handler) exit QEMU with a failure status.
#include <cstdint>

#include "port.hpp"

extern "C" {
// Linker script symbols (cortex_m4f.ld).
extern std::uint32_t __data_start[], __data_end[], __data_load[];
extern std::uint32_t __bss_start[], __bss_end[];
extern std::uint32_t __stack_limit[], __stack_top[];
using InitFn = void (*)();
extern InitFn __preinit_array_start[], __preinit_array_end[];
extern InitFn __init_array_start[], __init_array_end[];

int main();
void Reset_Handler();
[[noreturn]] void geojcbb_reset_continue();
void geojcbb_nmi();
void geojcbb_hard_fault();
void geojcbb_unexpected_irq();
}

namespace geojcbb::port {

namespace semihost {

[[noreturn]] void exit(std::uint32_t status) {
  // ARM semihosting: operation number in r0, parameter block address in r1, BKPT 0xAB (Thumb).
  constexpr std::uint32_t kSysExitExtended = 0x20;
  constexpr std::uint32_t kAdpStoppedApplicationExit = 0x20026;
  const std::uint32_t block[2] = {kAdpStoppedApplicationExit, status};
  register std::uint32_t r0 __asm("r0") = kSysExitExtended;
  register const std::uint32_t* r1 __asm("r1") = block;
  __asm volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
  for (;;) {  // not reached under QEMU with semihosting; elsewhere: stop here
    __asm volatile("wfi");
  }
}

}  // namespace semihost

namespace stack {

void install_guard() {
  // One MPU region over the lowest kGuardBytes of the stack: no access for anyone, never execute.
  // PRIVDEFENA keeps the default memory map everywhere else.
  static_assert(kGuardBytes == 32, "RASR.SIZE below encodes 32 bytes");
  const auto base = reinterpret_cast<std::uintptr_t>(__stack_limit);  // 32-byte aligned (linker check)
  constexpr std::uint32_t kSize32 = 4u << 1;                          // SIZE = 4: 2^(4+1) bytes
  constexpr std::uint32_t kApNoAccess = 0u << 24;
  constexpr std::uint32_t kXn = 1u << 28;
  constexpr std::uint32_t kEnable = 1u;
  if ((reg(scs::kMpuType) >> 8 & 0xFFu) == 0) return;  // no MPU: no guard
  reg(scs::kMpuRnr) = 0;
  reg(scs::kMpuRbar) = static_cast<std::uint32_t>(base);
  reg(scs::kMpuRasr) = kXn | kApNoAccess | kSize32 | kEnable;
  constexpr std::uint32_t kPrivDefEna = 1u << 2;
  reg(scs::kMpuCtrl) = kPrivDefEna | kEnable;
  __asm volatile("dsb\n\tisb" ::: "memory");
}

std::uint32_t capacity() {
  return static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(__stack_top) -
                                    reinterpret_cast<std::uintptr_t>(__stack_limit)) -
         kGuardBytes;
}

std::uint32_t high_water() {
  const volatile std::uint32_t* p = __stack_limit + kGuardBytes / 4;
  const volatile std::uint32_t* const top = __stack_top;
  while (p < top && *p == kPaint) ++p;  // <= capacity() / 4 reads
  return static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(top) - reinterpret_cast<std::uintptr_t>(p));
}

}  // namespace stack
}  // namespace geojcbb::port

using geojcbb::port::exit_status::kHardFault;
using geojcbb::port::exit_status::kMainReturned;
using geojcbb::port::exit_status::kNmi;
using geojcbb::port::exit_status::kUnexpectedIrq;

// The reset handler proper: FPU on and stack painted in assembly, so no compiled instruction (which
// may be a floating-point one, or may push to the stack) runs before them.
extern "C" __attribute__((naked, noreturn)) void Reset_Handler() {
  __asm volatile(
      "ldr r0, =0xE000ED88\n\t"  // CPACR
      "ldr r1, [r0]\n\t"
      "orr r1, r1, #(0xF << 20)\n\t"  // CP10, CP11: full access
      "str r1, [r0]\n\t"
      "dsb\n\t"
      "isb\n\t"
      "ldr r0, =__stack_limit\n\t"
      "ldr r1, =__stack_top\n\t"
      "ldr r2, =0x57AC57AC\n\t"  // stack::kPaint
      "1:\n\t"
      "cmp r0, r1\n\t"  // bound: (__stack_top - __stack_limit) / 4 stores
      "bhs 2f\n\t"
      "str r2, [r0], #4\n\t"
      "b 1b\n\t"
      "2:\n\t"
      "b geojcbb_reset_continue\n\t"
      ".ltorg");
}
static_assert(geojcbb::port::stack::kPaint == 0x57AC57ACu, "the reset handler paints with this word");

extern "C" [[noreturn]] void geojcbb_reset_continue() {
  // Copy .data, zero .bss: word loops through volatile pointers, so the compiler does not turn them
  // into memcpy/memset calls (picolibc's are fine, but this is before the C runtime is set up).
  volatile std::uint32_t* dst = __data_start;
  const volatile std::uint32_t* src = __data_load;
  geojcbb::port::board_early_init();
  while (dst < __data_end) *dst++ = *src++;                                  // <= sizeof(.data) / 4
  for (volatile std::uint32_t* p = __bss_start; p < __bss_end; ++p) *p = 0;  // <= sizeof(.bss) / 4
  geojcbb::port::stack::install_guard();
  for (InitFn* f = __preinit_array_start; f < __preinit_array_end; ++f) (*f)();  // <= array length
  for (InitFn* f = __init_array_start; f < __init_array_end; ++f) (*f)();        // <= array length
    // Calling main is the C runtime's job, and this is the C runtime: ISO C++ forbids it in a program
    // (-Wpedantic), so the one call is exempt.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpedantic"
  main();
#pragma GCC diagnostic pop
  geojcbb::port::semihost::exit(kMainReturned);
}

extern "C" void geojcbb_nmi() { geojcbb::port::semihost::exit(kNmi); }
extern "C" void geojcbb_hard_fault() { geojcbb::port::semihost::exit(kHardFault); }
extern "C" void geojcbb_unexpected_irq() { geojcbb::port::semihost::exit(kUnexpectedIrq); }
