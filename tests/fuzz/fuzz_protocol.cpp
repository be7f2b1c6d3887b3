// tests/fuzz: libFuzzer target for the serial link. The input is fed byte by byte to a Decoder
// (checking its invariants after every byte); every frame it yields goes to every message decoder,
// and so does the raw input as a payload (to reach validation without the CRC barrier). Whatever
// decodes is re-encoded and must give back the same payload bytes and, framed again, the same frame;
// a failed decode must leave its output untouched. Any violation: __builtin_trap.
// Built with -fsanitize=fuzzer,address,undefined under clang (GEOJCBB_FUZZ); corpus_runner.cpp runs it
// over tests/fuzz/corpus as a plain test in every build.
#include <array>
#include <cstddef>
#include <cstdint>

#include "geojcbb/protocol/protocol.hpp"

namespace {

using namespace geojcbb::proto;

void require(bool ok) {
  if (!ok) __builtin_trap();
}

bool same_bytes(const std::uint8_t* a, const std::uint8_t* b, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    if (a[i] != b[i]) return false;
  }
  return true;
}

/// Decodes p as message M; on success checks the payload and frame round trips, on failure that the
/// output is untouched.
template <class M>
void try_decode(const std::uint8_t* p, std::size_t n, std::uint8_t type, std::uint16_t seq, std::uint8_t fl) {
  M m{};
  std::array<std::uint8_t, M::kMaxPayloadSize + 1> before{};
  std::size_t before_len = 0;
  require(m.encode(before.data(), before.size(), before_len) == Error::kOk);  // defaults are valid

  const Error e = m.decode(p, n);
  std::array<std::uint8_t, M::kMaxPayloadSize + 1> again{};
  std::size_t again_len = 0;
  if (e != Error::kOk) {
    require(m.encode(again.data(), again.size(), again_len) == Error::kOk);
    require(again_len == before_len && same_bytes(again.data(), before.data(), before_len));
    return;
  }
  // Decoded: re-encoding gives the same bytes (the encoding is canonical).
  require(m.encode(again.data(), again.size(), again_len) == Error::kOk);
  require(again_len == n && same_bytes(again.data(), p, n));
  // And the frame round trip, when these bytes came in a frame of this type.
  if (type != static_cast<std::uint8_t>(M::kType)) return;
  EncodedFrame ef;
  require(encode_message(m, seq, fl, ef) == Error::kOk);
  Decoder d;
  FrameView f;
  std::size_t used = 0;
  require(d.push(ef.bytes.data(), ef.size, f, used) == Error::kOk);
  require(used == ef.size && f.type == type && f.seq == seq && f.flags == fl && f.len == n);
  require(same_bytes(f.payload, p, n));
  M back{};
  require(decode_message(f, back) == Error::kOk);
}

template <class... M>
void try_each(MessageList<M...>, const std::uint8_t* p, std::size_t n, std::uint8_t type, std::uint16_t seq,
              std::uint8_t fl) {
  (try_decode<M>(p, n, type, seq, fl), ...);
}

/// Every message of the schema, and the lists at other capacities.
void try_all(const std::uint8_t* p, std::size_t n, std::uint8_t type, std::uint16_t seq, std::uint8_t fl) {
  try_each(AllMessages<>{}, p, n, type, seq, fl);
  try_decode<ObsBatchT<1>>(p, n, type, seq, fl);
  try_decode<ObsBatchT<50>>(p, n, type, seq, fl);
  try_decode<AssocResultT<113>>(p, n, type, seq, fl);
}

std::uint64_t total(const DecoderCounters& c) {
  return std::uint64_t{c.frames_ok} + c.bad_crc + c.bad_length + c.overrun + c.bad_version + c.bad_flags;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Decoder d;
  for (std::size_t i = 0; i < size; ++i) {  // <= size
    const DecoderCounters prev = d.counters();
    FrameView f;
    const Error e = d.push(data[i], f);
    const DecoderCounters& now = d.counters();
    // Counters never decrease, and each event moves exactly one of them by one.
    require(now.frames_ok >= prev.frames_ok && now.bad_crc >= prev.bad_crc && now.bad_length >= prev.bad_length &&
            now.overrun >= prev.overrun && now.bad_version >= prev.bad_version && now.bad_flags >= prev.bad_flags);
    require(total(now) == total(prev) + (e == Error::kIncomplete ? 0 : 1));
    require(d.pending() <= kMaxEncodedBody);
    if (data[i] == kDelimiter) require(d.pending() == 0);
    if (e != Error::kOk) continue;
    require(now.frames_ok == prev.frames_ok + 1);
    require(f.len <= kMaxPayload && (f.payload != nullptr || f.len == 0));
    require((f.flags & flags::kIncompatibleMask) == 0);
    try_all(f.payload, f.len, f.type, f.seq, f.flags);
    int visits = 0;
    const Error de = dispatch(f, [&](const auto&) { ++visits; });
    require(visits == (de == Error::kOk ? 1 : 0));
    require(de != Error::kUnknownType || !is_known_type(f.type));
  }
  // The raw input as a payload: reaches every validator without the CRC barrier.
  if (size <= kMaxPayload) try_all(data, size, 0, 0, 0);
  return 0;
}
