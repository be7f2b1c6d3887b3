// tests/protocol: the schema text and its hash. HELLO's version and hash checks, the pinned hash,
// and that the hash covers what the wire depends on: message and field names, types, order and
// ranges (two descriptions of a test message that differ only by the order of two same-size fields
// hash differently).
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "protocol/protocol_fixtures.hpp"

using namespace proto_test;

TEST_CASE("protocol: HELLO version and schema hash") {
  CHECK(kProtocolVersion == 1);
  CHECK(kSchemaHash == fnv1a32(kSchemaText, kSchemaTextLength));
  // Pinned: if this fails, the schema text changed. That is the point: update docs/protocol.md
  // (hash value) and make sure both ends are rebuilt.
  CHECK(kSchemaHash == 0xF7A0130Cu);
  Hello h{};
  CHECK(check_hello(h) == Error::kOk);
  h.protocol_version = 2;
  CHECK(check_hello(h) == Error::kBadVersion);
  h = Hello{};
  h.schema_hash ^= 1u;
  CHECK(check_hello(h) == Error::kSchemaMismatch);
  // One character of the text changes the hash.
  std::string text(kSchemaText, kSchemaTextLength);
  text[text.find("OBS_BATCH")] = 'o';
  CHECK(fnv1a32(text.data(), text.size()) != kSchemaHash);
}

namespace {

// A test message described twice: the same members, two same-size fields in either order. Both
// descriptions give payloads of the same size, so a schema check that compares sizes cannot tell
// them apart; the wire differs, and so must the hash. The other variants change one attribute each
// of the first: a field's name, its type (i32 against u32, the same size), its range, the message's
// name.
enum class Variant { kFirstThenSecond, kSecondThenFirst, kRenamed, kRetyped, kRanged, kOtherName };
template <Variant V>
struct TestMsg : Codec<TestMsg<V>> {
  static constexpr MsgType kType = MsgType::kPing;
  static constexpr const char* kName = V == Variant::kOtherName ? "TEST2" : "TEST";

  std::uint32_t first = 0;
  std::conditional_t<V == Variant::kRetyped, std::int32_t, std::uint32_t> second = 0;

  static constexpr auto fields() {
    if constexpr (V == Variant::kSecondThenFirst) {
      return std::make_tuple(field("second", &TestMsg::second), field("first", &TestMsg::first));
    } else {
      return std::make_tuple(field("first", &TestMsg::first),
                             field(V == Variant::kRenamed ? "other" : "second", &TestMsg::second,
                                   V == Variant::kRanged ? range::at_least(1) : range::any()));
    }
  }
};
using FirstThenSecond = TestMsg<Variant::kFirstThenSecond>;
using SecondThenFirst = TestMsg<Variant::kSecondThenFirst>;
using Renamed = TestMsg<Variant::kRenamed>;
using Retyped = TestMsg<Variant::kRetyped>;
using Ranged = TestMsg<Variant::kRanged>;
using OtherName = TestMsg<Variant::kOtherName>;

template <class M>
std::string line_of() {
  const auto t = message_line<M>();
  REQUIRE(!t.overflow);
  return std::string(t.data.data(), t.size);
}

}  // namespace

TEST_CASE("protocol: swapping two same-size fields changes the wire and the schema hash") {
  static_assert(FirstThenSecond::kPayloadSize == SecondThenFirst::kPayloadSize, "same sizes");
  static_assert(message_hash<FirstThenSecond>() != message_hash<SecondThenFirst>(), "order is in the hash");
  CHECK(line_of<FirstThenSecond>() == "msg 0x06 TEST first:u32 second:u32\n");
  CHECK(line_of<SecondThenFirst>() == "msg 0x06 TEST second:u32 first:u32\n");
  CHECK(message_hash<FirstThenSecond>() != message_hash<SecondThenFirst>());
  // The two descriptions put the same struct on the wire differently.
  FirstThenSecond a{};
  a.first = 0x11111111u;
  a.second = 0x22222222u;
  SecondThenFirst b{};
  b.first = a.first;
  b.second = a.second;
  const Bytes pa = payload_of(a);
  const Bytes pb = payload_of(b);
  CHECK(pa.size() == pb.size());
  CHECK(pa != pb);
  CHECK(Bytes(pa.begin(), pa.begin() + 4) == Bytes(pb.begin() + 4, pb.end()));
  // Each attribute the wire depends on is in the hash.
  const std::uint32_t h = message_hash<FirstThenSecond>();
  CHECK(message_hash<Renamed>() != h);
  CHECK(message_hash<Retyped>() != h);
  CHECK(message_hash<Ranged>() != h);
  CHECK(message_hash<OtherName>() != h);
  CHECK(line_of<Retyped>() == "msg 0x06 TEST first:u32 second:i32\n");
  CHECK(line_of<Ranged>() == "msg 0x06 TEST first:u32 second:u32{>=1}\n");
  // The hash is the text's: every message's line is in kSchemaText, in schema order.
  const std::string text(kSchemaText, kSchemaTextLength);
  std::size_t at = text.find("\nmsg ");
  REQUIRE(at != std::string::npos);
  for (const std::string& line :
       {line_of<Hello>(),     line_of<Capabilities>(), line_of<Config>(),     line_of<Ack>(),
        line_of<Nack>(),      line_of<Ping>(),         line_of<Pong>(),       line_of<Reset>(),
        line_of<Shutdown>(),  line_of<Relocalise>(),   line_of<SubmapAck>(),  line_of<Odometry>(),
        line_of<OdomDelta>(), line_of<ObsBatch>(),     line_of<SubmapSeed>(), line_of<AssocResult>(),
        line_of<Pose>(),      line_of<Submap>(),       line_of<SubmapCov>(),  line_of<StatsRequest>(),
        line_of<Stats>(),     line_of<ErrorReport>()}) {
    CAPTURE(line);
    CHECK(text.compare(at + 1, line.size(), line) == 0);
    at += line.size();
  }
  CHECK(at + 1 == text.size());
  // A list's capacity is the receiver's, not part of the schema: every MaxObs renders the same line.
  CHECK(line_of<ObsBatchT<1>>() == line_of<ObsBatch>());
  CHECK(line_of<AssocResultT<113>>() == line_of<AssocResult>());
}

TEST_CASE("protocol: the schema text states each field's range as the validator checks it") {
  const std::string text(kSchemaText, kSchemaTextLength);
  // A few ranges of version 1, rendered from the descriptions (the validators use the same values;
  // test_messages.cpp checks the boundaries).
  for (const char* token :
       {" strategy:u8{0..6} ", " confidence:f32{(0,1)} ", " half_fov_rad:f32{(0,pi]} ", " bearing_rad:f32{[-pi,pi]} ",
        " d2:f32{>=0|+inf} ", " error:u8{2..17} ", " scalar_bytes:u8{4|8} ",
        " firmware_id:c16{printable,zero-padded}\n", " count:u8{<=capacity} repeat ", " condition_groups:u8{0|1} "}) {
    const std::string t = token;
    CAPTURE(t);
    CHECK(text.find(t) != std::string::npos);
  }
  for (const char* rule : {" {positive-definite}\nmsg 0x09 SHUTDOWN", " {max_range_m>min_range_m}\n",
                           " {diagonal>=0,count=min(removed,8)}\n"}) {
    const std::string r = rule;
    CAPTURE(r);
    CHECK(text.find(r) != std::string::npos);
  }
}
