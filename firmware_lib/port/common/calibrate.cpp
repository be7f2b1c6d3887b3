// port/common: SysTick calibration, built for each board. Under `-icount shift=0`, systick::instr_now()
// must count the instructions of a loop of known length: 2 * kIterations (subs, bne) plus the few
// instructions of instr_now itself. Writes the measured count to the board's UART (4 bytes,
// little-endian) and exits with 0 when it is within kTolerance of the expectation, 1 when below, 2
// when above.
#include <cstdint>

#include "port.hpp"

namespace {
constexpr std::uint32_t kIterations = 1'000'000;
constexpr std::uint32_t kExpected = 2 * kIterations;
// Two readings each quantised to one tick, plus instr_now's own instructions (about 20; with a
// fractional tick also the first reading's 64-bit conversion, a libgcc division, runs inside the
// measured interval: up to 200 more).
constexpr std::uint32_t kTolerance =
    3 * geojcbb::port::systick::kInstructionsPerTick + 40 + (geojcbb::port::systick::kInstrPerTickDen == 1 ? 0 : 200);
}  // namespace

int main() {
  namespace board = geojcbb::port;
  board::systick::start();
  board::uart::init(115200);
  std::uint32_t n = kIterations;
  const std::uint32_t t0 = board::systick::instr_now();
  __asm volatile(
      "1:\n\t"
      "subs %0, %0, #1\n\t"
      "bne 1b"
      : "+r"(n)
      :
      : "cc");
  const std::uint32_t t1 = board::systick::instr_now();
  const std::uint32_t d = t1 - t0;
  const std::uint8_t bytes[4] = {static_cast<std::uint8_t>(d), static_cast<std::uint8_t>(d >> 8),
                                 static_cast<std::uint8_t>(d >> 16), static_cast<std::uint8_t>(d >> 24)};
  board::uart::write(bytes, sizeof bytes);
  board::uart::flush();
  board::semihost::exit(d + kTolerance < kExpected ? 1u : d > kExpected + kTolerance ? 2u : 0u);
}
