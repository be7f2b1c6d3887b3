// mps2_an386: must NOT link. The board's linker script has no heap, so malloc (picolibc's sbrk needs
// __heap_start and __heap_end) is an undefined reference; the test firmware.mps2.malloc_fails_to_link
// builds this on purpose and expects exactly that error.
#include <cstdlib>

int main() {
  void* volatile p = std::malloc(16);
  return p != nullptr ? 0 : 1;
}
