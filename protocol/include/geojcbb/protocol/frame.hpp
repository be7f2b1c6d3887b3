// protocol: frames. A frame before COBS, little-endian:
//   ver u8 | flags u8 | type u8 | reserved u8 | seq u16 | len u16 | payload (len bytes) | crc32c u32
// CRC-32C covers every byte before it. On the wire: COBS(frame) then one 0x00 delimiter.
// Decoder takes one byte at a time into a fixed buffer (kMaxEncodedBody bytes), checks the frame at
// each delimiter and counts every rejection by cause; encode_frame writes header, payload and CRC
// straight through a streaming COBS encoder into a fixed output buffer. Bounds: kMaxPayload.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>

#include "geojcbb/protocol/cobs.hpp"
#include "geojcbb/protocol/crc32c.hpp"
#include "geojcbb/protocol/error.hpp"
#include "geojcbb/protocol/wire.hpp"

namespace geojcbb::proto {

constexpr std::uint8_t kProtocolVersion = 1;  ///< major version; a receiver drops any other
constexpr std::size_t kHeaderSize = 8;
constexpr std::size_t kCrcSize = 4;
constexpr std::size_t kMaxPayload = 1024;
constexpr std::size_t kMinFrameSize = kHeaderSize + kCrcSize;                ///< empty payload: 12
constexpr std::size_t kMaxFrameSize = kHeaderSize + kMaxPayload + kCrcSize;  ///< 1036
/// Largest COBS body a valid frame can have (what the decoder buffers before the delimiter).
constexpr std::size_t kMaxEncodedBody = cobs_max_encoded_size(kMaxFrameSize);  ///< 1041
/// Largest frame on the wire, delimiter included.
constexpr std::size_t kMaxEncodedFrame = kMaxEncodedBody + 1;  ///< 1042
constexpr std::uint8_t kDelimiter = 0x00;

static_assert(kMaxPayload <= std::numeric_limits<std::uint16_t>::max(), "len is a u16");
static_assert(kMaxEncodedBody == 1041 && kMaxEncodedFrame == 1042);

/// Wire size (delimiter included) of a frame carrying n payload bytes, worst case over contents.
constexpr std::size_t max_wire_size(std::size_t payload_bytes) {
  return cobs_max_encoded_size(kHeaderSize + payload_bytes + kCrcSize) + 1;
}

/// Header flag bits. Low nibble: compatible (a receiver ignores the ones it does not know). High
/// nibble: incompatible (a receiver drops a frame carrying one it does not know, and counts it).
namespace flags {
constexpr std::uint8_t kAckRequested = 0x01;  ///< compatible: sender asks for an ACK of this frame
constexpr std::uint8_t kCompatibleMask = 0x0F;
constexpr std::uint8_t kIncompatibleMask = 0xF0;
/// Incompatible flags this version understands: none yet. A future one (say, a compressed payload)
/// would be listed here, and older receivers drop such frames rather than misread them.
constexpr std::uint8_t kKnownIncompatible = 0x00;
}  // namespace flags

/// A checked frame: points into the Decoder's buffer, valid until the next push().
struct FrameView {
  std::uint8_t type = 0;
  std::uint8_t flags = 0;  ///< as received (unknown compatible bits included)
  std::uint16_t seq = 0;
  const std::uint8_t* payload = nullptr;
  std::uint16_t len = 0;  ///< payload bytes
};

/// One encoded frame, delimiter included, in a fixed buffer.
struct EncodedFrame {
  std::array<std::uint8_t, kMaxEncodedFrame> bytes{};
  std::size_t size = 0;
};

/// Frame encoder: header, payload and CRC-32C, COBS-stuffed, then the 0x00 delimiter.
/// @param[in] payload  len bytes (may be null when len is 0)
/// @param[out] out, cap  output buffer; kMaxEncodedFrame (or max_wire_size(len)) always suffices
/// @param[out] written  bytes written, delimiter included
/// @return kOk; kBadLength when len > kMaxPayload or payload is null with len > 0; kBufferTooSmall.
///         written is untouched on error.
[[nodiscard]] inline Error encode_frame(std::uint8_t type, std::uint16_t seq, std::uint8_t frame_flags,
                                        const std::uint8_t* payload, std::size_t len, std::uint8_t* out,
                                        std::size_t cap, std::size_t& written) {
  if (len > kMaxPayload || (payload == nullptr && len > 0)) return Error::kBadLength;
  if (out == nullptr || cap < 2) return Error::kBufferTooSmall;
  std::uint8_t header[kHeaderSize] = {kProtocolVersion, frame_flags, type, 0, 0, 0, 0, 0};
  put_u16_le(header + 4, seq);
  put_u16_le(header + 6, static_cast<std::uint16_t>(len));
  std::uint32_t crc = crc32c_update(kCrc32cInit, header, kHeaderSize);
  crc = crc32c_update(crc, payload, len);
  std::uint8_t trailer[kCrcSize] = {};
  put_u32_le(trailer, crc32c_final(crc));

  CobsEncoder enc(out, cap - 1);  // keep one byte for the delimiter
  enc.put(header, kHeaderSize);
  enc.put(payload, len);  // <= kMaxPayload
  enc.put(trailer, kCrcSize);
  const std::size_t body = enc.finish();
  if (body == 0) return Error::kBufferTooSmall;
  out[body] = kDelimiter;
  written = body + 1;
  return Error::kOk;
}

/// encode_frame into an EncodedFrame (cannot run out of room).
[[nodiscard]] inline Error encode_frame(std::uint8_t type, std::uint16_t seq, std::uint8_t frame_flags,
                                        const std::uint8_t* payload, std::size_t len, EncodedFrame& out) {
  std::size_t n = 0;
  const Error e = encode_frame(type, seq, frame_flags, payload, len, out.bytes.data(), out.bytes.size(), n);
  if (e == Error::kOk) out.size = n;
  return e;
}

/// Rejected frames by cause, as MAVLink keeps mavlink_status_t. Counters saturate at 2^32 - 1, so
/// they never decrease.
struct DecoderCounters {
  std::uint32_t frames_ok = 0;
  std::uint32_t bad_crc = 0;
  std::uint32_t bad_length = 0;  ///< COBS error, shorter than header + CRC, or len mismatch
  std::uint32_t overrun = 0;     ///< more than kMaxEncodedBody bytes before a delimiter
  std::uint32_t bad_version = 0;
  std::uint32_t bad_flags = 0;
};

/// Byte-at-a-time frame decoder (the MAVLink / nanopb shape). Holds one fixed buffer; never
/// allocates; never gets stuck: whatever happens, the next 0x00 starts a new frame. Back-to-back
/// delimiters (empty frames) are ignored and not counted. Checks, in order: COBS structure and
/// minimum size (bad_length), CRC (bad_crc), len field (bad_length), version (bad_version),
/// incompatible flags (bad_flags). CRC comes first so a corrupted frame counts as bad_crc whichever
/// field the corruption hit.
class Decoder {
 public:
  /// Feeds one byte.
  /// @param[out] frame  set only when kOk is returned; its payload points into this decoder and is
  ///                    valid until the next push()
  /// @return kOk (a frame is ready); kIncomplete (no frame yet, including an ignored empty frame and
  ///         the bytes of a frame already rejected for overrun); kOverrun (once per oversize frame,
  ///         at the byte that overflowed); kBadLength, kBadCrc, kBadVersion, kBadFlags (at the
  ///         delimiter of a rejected frame). Each error increments exactly one counter.
  [[nodiscard]] Error push(std::uint8_t byte, FrameView& frame) {
    if (byte != kDelimiter) {
      if (discarding_) return Error::kIncomplete;
      if (size_ >= buf_.size()) {
        discarding_ = true;
        size_ = 0;
        bump(counters_.overrun);
        return Error::kOverrun;
      }
      buf_[size_++] = byte;
      return Error::kIncomplete;
    }
    // Delimiter: whatever we held ends here.
    const std::size_t n = size_;
    size_ = 0;
    if (discarding_) {
      discarding_ = false;
      return Error::kIncomplete;
    }
    if (n == 0) return Error::kIncomplete;
    return check(n, frame);
  }

  /// Feeds [p, p + n) until the first frame or error. @param[out] consumed bytes taken, <= n
  /// @return as push(); kIncomplete when all n bytes were taken without an event.
  [[nodiscard]] Error push(const std::uint8_t* p, std::size_t n, FrameView& frame, std::size_t& consumed) {
    for (std::size_t i = 0; i < n; ++i) {  // <= n
      const Error e = push(p[i], frame);
      if (e != Error::kIncomplete) {
        consumed = i + 1;
        return e;
      }
    }
    consumed = n;
    return Error::kIncomplete;
  }

  /// Drops a partial frame (for example after a link timeout). Counters are kept.
  void reset() {
    size_ = 0;
    discarding_ = false;
  }

  [[nodiscard]] const DecoderCounters& counters() const { return counters_; }
  /// Bytes buffered for the frame in progress (<= kMaxEncodedBody).
  [[nodiscard]] std::size_t pending() const { return size_; }

 private:
  static void bump(std::uint32_t& c) {
    if (c != std::numeric_limits<std::uint32_t>::max()) ++c;
  }

  Error check(std::size_t n, FrameView& frame) {
    std::size_t m = 0;
    if (cobs_decode(buf_.data(), n, buf_.data(), buf_.size(), m) != Error::kOk || m < kMinFrameSize) {
      bump(counters_.bad_length);
      return Error::kBadLength;
    }
    const std::uint8_t* f = buf_.data();
    if (crc32c(f, m - kCrcSize) != get_u32_le(f + m - kCrcSize)) {
      bump(counters_.bad_crc);
      return Error::kBadCrc;
    }
    const std::uint16_t len = get_u16_le(f + 6);
    if (static_cast<std::size_t>(len) != m - kMinFrameSize || len > kMaxPayload) {
      bump(counters_.bad_length);
      return Error::kBadLength;
    }
    if (f[0] != kProtocolVersion) {
      bump(counters_.bad_version);
      return Error::kBadVersion;
    }
    if ((f[1] & flags::kIncompatibleMask & static_cast<std::uint8_t>(~flags::kKnownIncompatible)) != 0) {
      bump(counters_.bad_flags);
      return Error::kBadFlags;
    }
    bump(counters_.frames_ok);
    frame.flags = f[1];
    frame.type = f[2];
    frame.seq = get_u16_le(f + 4);
    frame.len = len;
    frame.payload = f + kHeaderSize;
    return Error::kOk;
  }

  std::array<std::uint8_t, kMaxEncodedBody> buf_{};
  std::size_t size_ = 0;
  bool discarding_ = false;
  DecoderCounters counters_{};
};

}  // namespace geojcbb::proto
