// protocol: Consistent Overhead Byte Stuffing (Cheshire and Baker, 1999). Removes every 0x00 from a
// frame so that 0x00 can delimit frames: a receiver resynchronises at the next 0x00 whatever came
// before. Overhead: a non-empty input of n bytes encodes to at most n + ceil(n / 254) bytes
// (cobs_max_encoded_size); the decoder can work in place (output never runs ahead of input).
// Encoding is streaming (CobsEncoder), so a frame is stuffed straight into the output buffer.
#pragma once

#include <cstddef>
#include <cstdint>

#include "geojcbb/protocol/error.hpp"

namespace geojcbb::proto {

/// Worst-case COBS size of n bytes, without the delimiter: n + ceil(n / 254), and 1 for n = 0.
constexpr std::size_t cobs_max_encoded_size(std::size_t n) { return n + (n == 0 ? 1 : (n + 253) / 254); }
static_assert(cobs_max_encoded_size(1) == 2 && cobs_max_encoded_size(254) == 255 && cobs_max_encoded_size(255) == 257);

/// Streams bytes into [out, out + cap) as COBS (no delimiter). Each block is a code byte followed by
/// up to 254 non-zero bytes; code c means "c - 1 data bytes follow, then a 0x00 unless c is 0xFF or
/// this is the last block". A full block is closed only when another byte follows, which is what
/// keeps the size at n + ceil(n / 254).
class CobsEncoder {
 public:
  CobsEncoder(std::uint8_t* out, std::size_t cap) : out_(out), cap_(cap) {
    if (out_ == nullptr || cap_ == 0) {
      ok_ = false;
    } else {
      pos_ = 1;  // out_[0] is the first code byte, written when its block closes
    }
  }

  void put(std::uint8_t b) {
    if (!ok_) return;
    if (code_ == 0xFF) close_block();  // the previous block is full and more data follows
    if (!ok_) return;
    if (b == 0) {
      close_block();
      return;
    }
    if (pos_ >= cap_) {
      ok_ = false;
      return;
    }
    out_[pos_++] = b;
    ++code_;
  }
  void put(const std::uint8_t* p, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) put(p[i]);  // <= n
  }
  /// Closes the last block. @return bytes written, or 0 when the output was too small.
  [[nodiscard]] std::size_t finish() {
    if (!ok_) return 0;
    out_[code_pos_] = code_;
    ok_ = false;  // finished: further puts are refused
    return pos_;
  }
  [[nodiscard]] bool ok() const { return ok_; }

 private:
  void close_block() {
    if (pos_ >= cap_) {
      ok_ = false;
      return;
    }
    out_[code_pos_] = code_;
    code_pos_ = pos_++;
    code_ = 1;
  }
  std::uint8_t* out_;
  std::size_t cap_;
  std::size_t pos_ = 0;
  std::size_t code_pos_ = 0;
  std::uint8_t code_ = 1;
  bool ok_ = true;
};

/// COBS-encodes [src, src + n) into [dst, dst + cap) (no delimiter).
/// @return kOk with out_len set; kBufferTooSmall (out_len untouched).
[[nodiscard]] inline Error cobs_encode(const std::uint8_t* src, std::size_t n, std::uint8_t* dst, std::size_t cap,
                                       std::size_t& out_len) {
  if (src == nullptr && n > 0) return Error::kBadLength;
  CobsEncoder enc(dst, cap);
  enc.put(src, n);
  const std::size_t written = enc.finish();
  if (written == 0) return Error::kBufferTooSmall;
  out_len = written;
  return Error::kOk;
}

/// Decodes COBS bytes [src, src + n) (delimiter excluded) into [dst, dst + cap). dst may equal src
/// (in place): every output byte is written at or before the input byte it came from.
/// @return kOk with out_len set; kBadLength for an empty input, a 0x00 inside the input or a block
///         that runs past the end; kBufferTooSmall. out_len is untouched on error (dst may not be).
[[nodiscard]] inline Error cobs_decode(const std::uint8_t* src, std::size_t n, std::uint8_t* dst, std::size_t cap,
                                       std::size_t& out_len) {
  if (src == nullptr || dst == nullptr || n == 0) return Error::kBadLength;
  std::size_t in = 0;
  std::size_t out = 0;
  while (in < n) {  // <= n iterations: every pass consumes at least the code byte
    const std::uint8_t code = src[in++];
    if (code == 0) return Error::kBadLength;
    const std::size_t run = static_cast<std::size_t>(code) - 1;
    if (run > n - in) return Error::kBadLength;
    if (run > cap - out) return Error::kBufferTooSmall;
    for (std::size_t k = 0; k < run; ++k) {  // <= 254
      const std::uint8_t b = src[in + k];
      if (b == 0) return Error::kBadLength;
      dst[out + k] = b;
    }
    in += run;
    out += run;
    if (code != 0xFF && in < n) {
      if (out >= cap) return Error::kBufferTooSmall;
      dst[out++] = 0;
    }
  }
  out_len = out;
  return Error::kOk;
}

}  // namespace geojcbb::proto
