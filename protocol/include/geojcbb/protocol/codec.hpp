// protocol: messages to frames and back. encode_message turns a message struct into a wire frame;
// decode_message checks a decoded frame's type and decodes its payload; dispatch decodes a frame of
// any known type and hands the message to a visitor. MessageCounters counts what the message layer
// rejects (unknown types, invalid payloads), the layer above Decoder's framing counters.
// Bounds: the payload scratch is sized per message at compile time (Msg::kMaxPayloadSize).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>

#include "geojcbb/protocol/error.hpp"
#include "geojcbb/protocol/frame.hpp"
#include "geojcbb/protocol/messages.hpp"

namespace geojcbb::proto {

/// Validates and encodes m, then frames it (header, CRC-32C, COBS, delimiter).
/// @param[out] out  written only on kOk
/// @return kOk; m's validation error; kBufferTooSmall (cap too small).
template <class Msg>
[[nodiscard]] Error encode_message(const Msg& m, std::uint16_t seq, std::uint8_t frame_flags, std::uint8_t* out,
                                   std::size_t cap, std::size_t& written) {
  std::array<std::uint8_t, Msg::kMaxPayloadSize> payload{};
  std::size_t n = 0;
  const Error e = m.encode(payload.data(), payload.size(), n);
  if (e != Error::kOk) return e;
  return encode_frame(static_cast<std::uint8_t>(Msg::kType), seq, frame_flags, payload.data(), n, out, cap, written);
}
template <class Msg>
[[nodiscard]] Error encode_message(const Msg& m, std::uint16_t seq, std::uint8_t frame_flags, EncodedFrame& out) {
  std::size_t n = 0;
  const Error e = encode_message(m, seq, frame_flags, out.bytes.data(), out.bytes.size(), n);
  if (e == Error::kOk) out.size = n;
  return e;
}

/// Decodes a checked frame as message type Msg.
/// @return kOk; kUnknownType (not a type of this schema); kWrongType (a known type, not Msg's);
///         Msg's decode errors. out is untouched on error.
template <class Msg>
[[nodiscard]] Error decode_message(const FrameView& f, Msg& out) {
  if (!is_known_type(f.type)) return Error::kUnknownType;
  if (f.type != static_cast<std::uint8_t>(Msg::kType)) return Error::kWrongType;
  return out.decode(f.payload, f.len);
}

/// Rejections above the framing layer, as STATS reports them.
struct MessageCounters {
  std::uint32_t unknown_type = 0;
  std::uint32_t invalid_field = 0;  ///< payload length, count, NaN/Inf, range or definiteness

  /// Counts the outcome of decode_message or dispatch (kOk and kWrongType count nothing).
  void record(Error e) {
    switch (e) {
      case Error::kUnknownType: bump(unknown_type); break;
      case Error::kBadLength:
      case Error::kNonFinite:
      case Error::kOutOfRange:
      case Error::kCapacityExceeded:
      case Error::kNotPositiveDefinite: bump(invalid_field); break;
      default: break;
    }
  }

 private:
  static void bump(std::uint32_t& c) {
    if (c != std::numeric_limits<std::uint32_t>::max()) ++c;
  }
};

namespace detail {
/// Decodes f as M into a local and calls the visitor with it (a function per type, so each message's
/// temporary lives in its own frame, not all of them in the caller's).
template <class M, class Visitor>
[[nodiscard]] Error visit_as(const FrameView& f, Visitor& visitor) {
  M msg{};
  const Error e = msg.decode(f.payload, f.len);
  if (e == Error::kOk) visitor(static_cast<const M&>(msg));
  return e;
}
template <class Visitor, class... M>
[[nodiscard]] Error dispatch_over(const FrameView& f, Visitor& visitor, MessageList<M...>) {
  Error e = Error::kUnknownType;
  (void)((f.type == static_cast<std::uint8_t>(M::kType) && ((e = visit_as<M>(f, visitor)), true)) || ...);
  return e;
}
}  // namespace detail

/// Decodes a frame of any known type and calls visitor(const Msg&) with it. The visitor must accept
/// every message type (a generic lambda does). Nothing is called on error.
/// @tparam MaxObs  capacity of OBS_BATCH and ASSOC_RESULT on this side of the link
/// @return kOk; kUnknownType; the message's decode error.
template <std::size_t MaxObs = kDefaultMaxObsPerBatch, class Visitor>
[[nodiscard]] Error dispatch(const FrameView& f, Visitor&& visitor) {
  return detail::dispatch_over(f, visitor, AllMessages<MaxObs>{});
}

}  // namespace geojcbb::proto
