// protocol: the one list of outcomes of every framing and message call. The protocol depends on the
// C++ standard library only, so it has its own enum rather than geojcbb::Status. A call that returns
// anything but kOk has left its outputs untouched. The values travel in NACK and ERROR messages, so
// they are part of the schema (schema.hpp lists them; renumbering changes the schema hash).
#pragma once

#include <cstdint>

namespace geojcbb::proto {

enum class [[nodiscard]] Error : std::uint8_t{
    kOk = 0,
    kIncomplete = 1,            ///< Decoder::push: no complete frame yet (not a fault, never counted)
    kBadLength = 2,             ///< COBS error, frame too short, len field or payload size inconsistent
    kBadCrc = 3,                ///< CRC-32C mismatch
    kOverrun = 4,               ///< frame longer than the receive buffer before its delimiter
    kBadVersion = 5,            ///< protocol major version not ours
    kBadFlags = 6,              ///< an incompatible flag we do not know
    kUnknownType = 7,           ///< message type number not in the schema
    kWrongType = 8,             ///< a known type, but not the one the caller asked to decode
    kNonFinite = 9,             ///< NaN or Inf in a float field that must be finite
    kOutOfRange = 10,           ///< a field outside its valid range (see docs/protocol.md)
    kCapacityExceeded = 11,     ///< a count over a compile-time capacity
    kNotPositiveDefinite = 12,  ///< a covariance that is not positive definite
    kBufferTooSmall = 13,       ///< caller's output buffer cannot hold the result
    kSchemaMismatch = 14,       ///< HELLO with another schema hash
    kNotReady = 15,             ///< device: a stream message before CONFIG and RESET
    kInternal = 16,             ///< device: the pipeline refused a valid message
    kBusy = 17,                 ///< device: a stream frame during a map hand-over (not applied: send it again)
};
/// One past the largest value; a u8 on the wire at or above this is not an Error.
constexpr std::uint8_t kErrorCount = 18;

/// Short stable name, for logs and test messages (no allocation).
constexpr const char* to_string(Error e) {
  switch (e) {
    case Error::kOk: return "ok";
    case Error::kIncomplete: return "incomplete";
    case Error::kBadLength: return "bad-length";
    case Error::kBadCrc: return "bad-crc";
    case Error::kOverrun: return "overrun";
    case Error::kBadVersion: return "bad-version";
    case Error::kBadFlags: return "bad-flags";
    case Error::kUnknownType: return "unknown-type";
    case Error::kWrongType: return "wrong-type";
    case Error::kNonFinite: return "non-finite";
    case Error::kOutOfRange: return "out-of-range";
    case Error::kCapacityExceeded: return "capacity-exceeded";
    case Error::kNotPositiveDefinite: return "not-positive-definite";
    case Error::kBufferTooSmall: return "buffer-too-small";
    case Error::kSchemaMismatch: return "schema-mismatch";
    case Error::kNotReady: return "not-ready";
    case Error::kInternal: return "internal";
    case Error::kBusy: return "busy";
  }
  return "unknown";
}

}  // namespace geojcbb::proto
