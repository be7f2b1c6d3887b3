// port/common: the firmware, shared by the boards. The device loop (node::Node, float) on the board's
// UART (mps2-an386: UART0; netduinoplus2: USART1).
//   GEOJCBB_BOARD_BOUNDS  the configuration's Bounds type (the board's CMakeLists.txt)
// All pipeline memory is the one static Node, sized by the bounds (.bss). The loop drains the
// receive ring into Node::on_bytes and sleeps (WFI) when it is empty; after each chunk that ends a
// frame it measures the stack's high-water mark and hands it to the Node (STATS reports it). A
// SHUTDOWN message exits QEMU through semihosting with the requested status.
// Boot id: a boot counter in .noinit RAM (kept across resets within one QEMU process, zero on a
// fresh one) mixed with the instruction count at the first received byte (under icount the virtual
// clock runs with real time while the core sleeps, so it differs from boot to boot).
#include <cstddef>
#include <cstdint>

#include "geojcbb/node/node.hpp"
#include "port.hpp"

#ifndef GEOJCBB_BOARD_BOUNDS
#error "GEOJCBB_BOARD_BOUNDS: the configuration's geojcbb::Bounds type"
#endif

namespace {

namespace board = geojcbb::port;
using BoardBounds = GEOJCBB_BOARD_BOUNDS;
using BoardNode = geojcbb::node::Node<float, BoardBounds>;

constexpr std::uint32_t kBaud = 115200;  // nominal: QEMU does not pace the UART
constexpr std::uint32_t kBootMagic = 0xB0075EEDu;

BoardNode g_node;

struct BootRecord {
  std::uint32_t magic;
  std::uint32_t count;
};
__attribute__((section(".noinit"))) BootRecord g_boot;

void write_bytes(void*, const std::uint8_t* data, std::size_t n) { board::uart::write(data, n); }

[[noreturn]] void shutdown(void*, std::uint8_t exit_code) {
  board::uart::flush();  // the ACK has been written; let its last byte leave
  board::semihost::exit(exit_code);
}

std::uint32_t count_boot() {
  if (g_boot.magic != kBootMagic) {
    g_boot.magic = kBootMagic;
    g_boot.count = 0;
  }
  g_boot.count = g_boot.count + 1;
  return g_boot.count;
}

std::uint32_t mix(std::uint32_t a, std::uint32_t b) {
  std::uint32_t h = a * 0x9E3779B1u ^ b;
  h ^= h >> 16;
  h *= 0x85EBCA6Bu;
  h ^= h >> 13;
  h *= 0xC2B2AE35u;
  h ^= h >> 16;
  return h;
}

bool has_delimiter(const std::uint8_t* p, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {  // <= n
    if (p[i] == geojcbb::proto::kDelimiter) return true;
  }
  return false;
}

}  // namespace

int main() {
  const std::uint32_t boot_count = count_boot();
  board::systick::start();
  board::uart::init(kBaud);
  bool started = false;
  for (;;) {  // until SHUTDOWN (semihosting exit); one pass per received chunk or wake-up
    const std::uint8_t* data = nullptr;
    const std::size_t n = board::uart::rx_peek(&data);
    if (n == 0) {
      board::uart::wait_for_rx();
      continue;
    }
    if (!started) {  // first byte: the boot id can now include the time it arrived
      geojcbb::node::Output out;
      out.write = write_bytes;
      out.shutdown = shutdown;
      g_node.start(out, mix(boot_count, board::systick::instr_now()), board::systick::instr_now);
      started = true;
    }
    g_node.on_bytes(data, n);
    const bool frame_end = has_delimiter(data, n);
    board::uart::rx_release(n);
    if (frame_end) g_node.set_stack_high_water(board::stack::high_water());
  }
}
