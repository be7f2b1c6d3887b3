// FaultTransport: bytes dropped and corrupted on their way, as on a real robot's UART. Over an
// in-memory loopback: the fault events' rate and mix against their binomial expectations, the same
// seed giving the same faults (and a reopened port continuing them), rate 0 changing nothing, and the
// spec's parser. Over a pty to the desktop device through a LinkSession: a faulty link's replies
// against a clean link's, scan by scan, and the link's counters against the faults injected.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "geojcbb_host/fault_transport.hpp"
#include "geojcbb_host/session.hpp"
#include "support/pty_device.hpp"

using namespace geojcbb;
using namespace geojcbb::host;

namespace {

/// What is written can be read back, in order (a wire looped back on itself).
class Loopback : public Transport {
 public:
  std::size_t read(std::uint8_t* p, std::size_t n, int /*timeout_ms*/) override {
    std::size_t k = 0;
    for (; k < n && !q_.empty(); ++k) {
      p[k] = q_.front();
      q_.pop_front();
    }
    return k;
  }
  void write(const std::uint8_t* p, std::size_t n) override { q_.insert(q_.end(), p, p + n); }

 private:
  std::deque<std::uint8_t> q_;
};

std::vector<std::uint8_t> random_bytes(std::size_t n, std::uint64_t seed) {
  std::mt19937_64 g(seed);
  std::vector<std::uint8_t> v(n);
  for (auto& b : v) b = static_cast<std::uint8_t>(g());
  return v;
}

/// Writes `in` through a FaultTransport on a loopback in chunks of `chunk`, then reads everything
/// back through it (so both directions' faults apply): what came out.
std::vector<std::uint8_t> through(FaultTransport& t, const std::vector<std::uint8_t>& in, std::size_t chunk = 997) {
  for (std::size_t at = 0; at < in.size(); at += chunk) t.write(in.data() + at, std::min(chunk, in.size() - at));
  std::vector<std::uint8_t> out;
  std::uint8_t buf[613];
  while (const std::size_t n = t.read(buf, sizeof buf, 0)) out.insert(out.end(), buf, buf + n);
  return out;
}

/// |k - n p| within 5 binomial standard deviations.
void check_binomial(std::uint64_t k, std::uint64_t n, double p) {
  const double mean = static_cast<double>(n) * p;
  const double sigma = std::sqrt(mean * (1 - p));
  CAPTURE(k);
  CAPTURE(n);
  CAPTURE(p);
  CHECK(std::abs(static_cast<double>(k) - mean) <= 5 * sigma);
}

}  // namespace

TEST_CASE("fault transport: fault events at the byte error rate, drops, flips and bursts in their mix") {
  LinkFaults f;
  f.byte_error_rate = 1e-3;
  f.drop_fraction = 0.3;
  f.burst_fraction = 0.2;
  f.seed = 11;
  const std::vector<std::uint8_t> in = random_bytes(1000000, 5);
  FaultTransport t(std::make_unique<Loopback>(), f);
  const std::vector<std::uint8_t> out = through(t, in);
  const FaultCounts& c = t.counts();
  for (const FaultDirectionCounts* d : {&c.to_device, &c.from_device}) {
    CHECK(d->events() > 500);
    // An event starts at a byte outside a burst with probability ber; a burst with burst_fraction.
    check_binomial(d->events(), d->trials(), f.byte_error_rate);
    check_binomial(d->bursts, d->events(), f.burst_fraction);
    // Every byte hit (a single event's or a burst's) is dropped with drop_fraction, else flipped.
    check_binomial(d->dropped, d->dropped + d->corrupted, f.drop_fraction);
    // Burst lengths uniform in [8, 64]: mean 36, variance (57^2 - 1) / 12 (the last may be cut short).
    const double mean = 36.0 * static_cast<double>(d->bursts);
    const double sigma = std::sqrt((57.0 * 57.0 - 1) / 12 * static_cast<double>(d->bursts));
    CHECK(std::abs(static_cast<double>(d->burst_bytes) - mean) <= 5 * sigma + 64);
  }
  CHECK(c.to_device.bytes() == in.size());
  CHECK(c.from_device.bytes() == c.to_device.passed + c.to_device.corrupted);  // what was written is read
  CHECK(out.size() == c.from_device.passed + c.from_device.corrupted);
  MESSAGE(c.describe());
}

TEST_CASE("fault transport: a flip changes one bit of one byte; a drop removes the byte") {
  LinkFaults f;
  f.byte_error_rate = 1e-2;
  f.burst_fraction = 0;
  f.drop_fraction = 0;  // flips only: the output lines up with the input
  f.seed = 3;
  const std::vector<std::uint8_t> in = random_bytes(100000, 9);
  FaultTransport t(std::make_unique<Loopback>(), f);
  const std::vector<std::uint8_t> out = through(t, in);
  REQUIRE(out.size() == in.size());
  std::uint64_t differ = 0, one_bit = 0;
  for (std::size_t i = 0; i < in.size(); ++i) {
    const unsigned x = in[i] ^ out[i];
    differ += x != 0;
    one_bit += x != 0 && (x & (x - 1)) == 0;
  }
  // A byte hit in both directions may come back whole (the same bit twice) or with two bits changed.
  const FaultCounts& c = t.counts();
  CHECK(c.to_device.dropped + c.from_device.dropped == 0);
  CHECK(differ <= c.to_device.corrupted + c.from_device.corrupted);
  // About 1e-2 * 1e-2 * 1e5 = 10 bytes are hit in both directions (at most 30: 5 sigma).
  CHECK(differ + 2 * 30 >= c.to_device.corrupted + c.from_device.corrupted);
  CHECK(one_bit + 30 >= differ);

  f.drop_fraction = 1;  // drops only: the output is the input less some bytes, in order
  FaultTransport d(std::make_unique<Loopback>(), f);
  const std::vector<std::uint8_t> kept = through(d, in);
  CHECK(kept.size() == in.size() - d.counts().to_device.dropped - d.counts().from_device.dropped);
  CHECK(d.counts().to_device.corrupted + d.counts().from_device.corrupted == 0);
  std::size_t j = 0;
  for (std::size_t i = 0; i < in.size() && j < kept.size(); ++i) j += in[i] == kept[j];
  CHECK(j == kept.size());  // a subsequence
}

TEST_CASE("fault transport: the same seed gives the same faults; another seed others; a reopened port continues") {
  LinkFaults f;
  f.byte_error_rate = 2e-3;
  f.seed = 7;
  const std::vector<std::uint8_t> in = random_bytes(300000, 1);
  FaultTransport a(std::make_unique<Loopback>(), f);
  FaultTransport b(std::make_unique<Loopback>(), f);
  const std::vector<std::uint8_t> out_a = through(a, in);
  CHECK(out_a != in);
  CHECK(through(b, in, 4096) == out_a);  // chunking does not matter: the faults follow the bytes
  CHECK(b.counts().describe() == a.counts().describe());
  f.seed = 8;
  FaultTransport c(std::make_unique<Loopback>(), f);
  CHECK(through(c, in) != out_a);
  CHECK(c.counts().describe() != a.counts().describe());

  // One line, two transports one after the other: what one transport over all the bytes does.
  f.seed = 7;
  auto line = std::make_shared<FaultLine>(f);
  std::vector<std::uint8_t> two;
  {
    FaultTransport first(std::make_unique<Loopback>(), line);
    two = through(first, std::vector<std::uint8_t>(in.begin(), in.begin() + 100000));
  }
  FaultTransport second(std::make_unique<Loopback>(), line);
  const std::vector<std::uint8_t> rest = through(second, std::vector<std::uint8_t>(in.begin() + 100000, in.end()));
  two.insert(two.end(), rest.begin(), rest.end());
  // Each direction's faults follow its byte sequence, which is the same: the same counts, the same output.
  CHECK(line->counts.to_device.bytes() == in.size());
  CHECK(line->counts.to_device.dropped == a.counts().to_device.dropped);
  CHECK(line->counts.to_device.corrupted == a.counts().to_device.corrupted);
  CHECK(line->counts.to_device.bursts == a.counts().to_device.bursts);
  CHECK(line->counts.from_device.bytes() == a.counts().from_device.bytes());
  CHECK(two == out_a);
}

TEST_CASE("fault transport: rate 0 passes every byte unchanged") {
  const std::vector<std::uint8_t> in = random_bytes(200000, 2);
  LinkFaults f;  // byte_error_rate 0
  CHECK_FALSE(f.injects());
  FaultTransport t(std::make_unique<Loopback>(), f);
  CHECK(through(t, in) == in);
  CHECK(t.counts().to_device.passed == in.size());
  CHECK(t.counts().from_device.passed == in.size());
  CHECK(t.counts().to_device.events() + t.counts().from_device.events() == 0);
  CHECK(t.counts().to_device.dropped + t.counts().to_device.corrupted + t.counts().to_device.bursts == 0);
}

TEST_CASE("fault transport: the spec string") {
  const LinkFaults f = parse_link_faults("ber=1e-4,drop=0.5,burst=0.1,seed=7,reset=120");
  // describe() names every field, each as the shortest decimal that reads back as its value.
  CHECK(f.describe() == "ber=0.0001,drop=0.5,burst=0.1,burst_min=8,burst_max=64,seed=7,reset=120");
  const LinkFaults g = parse_link_faults(" ber = 3.3e-5 , burst_min=1, burst_max=2,seed=18446744073709551615");
  CHECK(g.byte_error_rate == 3.3e-5);
  CHECK(g.burst_min == 1);
  CHECK(g.burst_max == 2);
  CHECK(g.seed == 18446744073709551615ULL);
  const LinkFaults back = parse_link_faults(g.describe());
  CHECK(back.describe() == g.describe());
  CHECK(back.byte_error_rate == g.byte_error_rate);
  CHECK_FALSE(parse_link_faults("").injects());
  CHECK_FALSE(parse_link_faults("none").injects());
  CHECK(parse_link_faults("ber=0").describe() == LinkFaults{}.describe());

  CHECK_THROWS_WITH_AS(parse_link_faults("ber=2"), doctest::Contains("ber=2: outside [0, 1]"), std::invalid_argument);
  CHECK_THROWS_WITH_AS(parse_link_faults("ber=x"), doctest::Contains("ber=x: not a number"), std::invalid_argument);
  CHECK_THROWS_WITH_AS(parse_link_faults("ber=nan"), doctest::Contains("ber=nan: not a number"), std::invalid_argument);
  CHECK_THROWS_WITH_AS(parse_link_faults("drop=-0.1"), doctest::Contains("drop=-0.1"), std::invalid_argument);
  CHECK_THROWS_WITH_AS(parse_link_faults("burts=0.1"), doctest::Contains("unknown key 'burts'"), std::invalid_argument);
  CHECK_THROWS_WITH_AS(parse_link_faults("seed=-1"), doctest::Contains("seed=-1: not an unsigned integer"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS(parse_link_faults("seed=1.5"), doctest::Contains("seed=1.5"), std::invalid_argument);
  CHECK_THROWS_WITH_AS(parse_link_faults("burst_min=0"), doctest::Contains("burst_min=0: outside"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS(parse_link_faults("burst_min=10,burst_max=9"),
                       doctest::Contains("burst_min=10 is over burst_max=9"), std::invalid_argument);
  CHECK_THROWS_WITH_AS(parse_link_faults("ber=1e-4,ber=1e-3"), doctest::Contains("ber=1e-3: given twice"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS(parse_link_faults("ber"), doctest::Contains("'ber' is not key=value"), std::invalid_argument);
  CHECK_THROWS_WITH_AS(parse_link_faults("ber=1e-4,"), doctest::Contains("is not key=value"), std::invalid_argument);
  CHECK_THROWS_WITH_AS(parse_link_faults("reset=-5"), doctest::Contains("reset=-5: outside"), std::invalid_argument);
}

namespace {

/// The frames written to a transport, as they decode: seq -> type, and OBS_BATCH seq -> batch id.
struct FrameLog {
  proto::Decoder dec;
  std::map<std::uint16_t, std::uint8_t> type;
  std::map<std::uint16_t, std::uint32_t> batch;
  std::uint16_t last_config = 0;
  void feed(const std::uint8_t* p, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) {
      proto::FrameView f;
      if (dec.push(p[i], f) != proto::Error::kOk) continue;
      type[f.seq] = f.type;
      LinkObsBatch b;
      if (f.type == static_cast<std::uint8_t>(proto::MsgType::kObsBatch) &&
          b.decode(f.payload, f.len) == proto::Error::kOk) {
        batch[f.seq] = b.batch_id;
      }
      if (f.type == static_cast<std::uint8_t>(proto::MsgType::kConfig)) last_config = f.seq;
    }
  }
};

/// Logs what is written through it (reads pass).
class Tap : public Transport {
 public:
  Tap(std::unique_ptr<Transport> inner, FrameLog& log) : inner_(std::move(inner)), log_(log) { log_.dec = {}; }
  std::size_t read(std::uint8_t* p, std::size_t n, int timeout_ms) override { return inner_->read(p, n, timeout_ms); }
  void write(const std::uint8_t* p, std::size_t n) override {
    log_.feed(p, n);
    inner_->write(p, n);
  }

 private:
  std::unique_ptr<Transport> inner_;
  FrameLog& log_;
};

/// Every scored reply of a run through a LinkSession, by batch id (a restarted run's replies replace
/// the earlier attempt's), as the payload bytes of its ASSOC_RESULT and POSE.
struct LinkRun {
  RunResult result;
  std::map<std::uint32_t, std::vector<std::uint8_t>> replies;
  std::vector<std::string> notes;
  int reconnections = 0, restarts = 0;
  std::uint64_t duplicates = 0;
  proto::DecoderCounters host;  ///< the host's decoder
  proto::Stats device;          ///< the device's STATS after the run
  FrameLog sent, arrived;       ///< frames the host wrote, and those that reached the device intact
};

template <class M>
void append_payload(const M& m, std::vector<std::uint8_t>& out) {
  std::vector<std::uint8_t> p(M::kMaxPayloadSize);
  std::size_t n = 0;
  REQUIRE(m.encode(p.data(), p.size(), n) == proto::Error::kOk);
  out.insert(out.end(), p.begin(), p.begin() + static_cast<std::ptrdiff_t>(n));
}

/// env1, seed 3, the whole lap (737 scans), one batch in flight, to a desktop device on a pty; with a
/// fault line, every port the session opens goes through it.
std::unique_ptr<LinkRun> run_link(const std::shared_ptr<FaultLine>& line, std::uint32_t boot_id) {
  static const Scenario sc = load_scenario(std::string(GEOJCBB_SCENARIO_DIR) + "/env1.json");
  test::PtyDevice dev(boot_id);
  auto out = std::make_unique<LinkRun>();
  SessionOptions so;
  const std::string path = dev.pty.slave_path();
  LinkRun* r = out.get();
  so.open = [path, line, r]() -> std::unique_ptr<Transport> {
    std::unique_ptr<Transport> port = std::make_unique<Tap>(std::make_unique<PosixSerial>(path), r->arrived);
    if (line) port = std::make_unique<FaultTransport>(std::move(port), line);
    return std::make_unique<Tap>(std::move(port), r->sent);
  };
  so.timeout_ms = 400;
  so.reconnect_ms = 5000;
  so.note = [r](const std::string& s) { r->notes.push_back(s); };
  LinkSession session(so);
  SimSource src(sc, 3);
  RunOptions o;
  o.step.strategy = Strategy::kGeojcbb;
  StreamOptions st;
  st.hook = [r](const LinkObsBatch& b, const LinkClient::ScanReply& reply) {
    std::vector<std::uint8_t>& v = r->replies[b.batch_id];
    v.clear();
    append_payload(reply.result, v);
    append_payload(reply.pose, v);
  };
  out->result = stream_run(session, src, o, st);
  out->device = session.stats();
  out->reconnections = session.reconnections();
  out->restarts = session.restarts();
  out->duplicates = session.client().duplicate_replies();
  out->host = session.client().frame_counters();
  return out;
}

std::uint64_t rejected(const proto::DecoderCounters& c) {
  return std::uint64_t{c.bad_crc} + c.bad_length + c.overrun + c.bad_version + c.bad_flags;
}

std::string summary(const LinkRun& r, const FaultCounts& c) {
  std::ostringstream s;
  s << "injected: " << c.describe() << "\nhost decoder: " << rejected(r.host) << " frames rejected (" << r.host.bad_crc
    << " bad CRC, " << r.host.bad_length << " bad length, " << r.host.overrun << " overrun), " << r.host.frames_ok
    << " taken\ndevice: " << describe_stats(r.device) << "\nsession: " << r.reconnections << " reconnections, "
    << r.restarts << " restarts, " << r.duplicates << " duplicate replies";
  return s.str();
}

/// Batches whose replies differ from the clean run's (or are missing).
std::vector<std::uint32_t> differing(const LinkRun& clean, const LinkRun& faulty) {
  std::vector<std::uint32_t> out;
  for (const auto& [id, bytes] : clean.replies) {
    const auto it = faulty.replies.find(id);
    if (it == faulty.replies.end() || it->second != bytes) out.push_back(id);
  }
  return out;
}

const LinkRun& clean_run() {
  static const std::unique_ptr<LinkRun> clean = run_link(nullptr, 0xC1EA);
  return *clean;
}

}  // namespace

TEST_CASE("fault transport: replies damaged at byte error rate 1e-4 with bursts: every reply as on a clean link") {
  const LinkRun& clean = clean_run();
  CHECK(clean.result.scans == 737);
  CHECK(clean.replies.size() == 737);
  CHECK(clean.reconnections == 0);
  CHECK(rejected(clean.host) == 0);
  CHECK(clean.device.bad_crc + clean.device.bad_length + clean.device.overrun == 0);

  // Faults on what the device sends only: every frame the host writes arrives.
  auto line = std::make_shared<FaultLine>(parse_link_faults("ber=1e-4,drop=0.5,burst=0.1,seed=7"));
  line->to_device = FaultChannel(LinkFaults{}, 0);
  const std::unique_ptr<LinkRun> faulty = run_link(line, 0xFA17);
  const FaultCounts& c = line->counts;
  MESSAGE(summary(*faulty, c));
  CHECK(faulty->result.scans == clean.result.scans);
  CHECK(faulty->replies.size() == clean.replies.size());
  CHECK(differing(clean, *faulty).empty());
  CHECK(faulty->result.score.tp == clean.result.score.tp);
  CHECK(faulty->result.score.fp == clean.result.score.fp);
  CHECK(faulty->result.score.fn == clean.result.score.fn);
  CHECK(faulty->result.mean_abs_x_m == clean.result.mean_abs_x_m);
  // The faults happened and the link saw them: frames rejected by the host's decoder, the session
  // recovered by reconnecting and resending (the device sends the last batch's replies again).
  CHECK(c.to_device.events() == 0);
  CHECK(c.from_device.events() > 0);
  CHECK(rejected(faulty->host) > 0);
  CHECK(faulty->reconnections > 0);
  CHECK(faulty->device.bad_crc + faulty->device.bad_length + faulty->device.overrun == 0);
}

// Both ways, the link recovers every frame but one kind: an ODOMETRY that does not arrive is never
// noticed (it has no reply; the next OBS_BATCH is applied and answered as usual, and a later resend
// of the ODOMETRY is older than the frames applied since, so the device ignores it). The device's
// pose then misses that motion, and every reply from that scan on differs, with nothing on the link
// saying so (docs/protocol.md, "Fault injection"). This test holds that exactly: every other frame
// reaches the device, and the replies equal the clean run's up to the scan after the first lost
// ODOMETRY. When the protocol detects a lost ODOMETRY, the replies must all be equal here.
TEST_CASE(
    "fault transport: both ways at 1e-4 with bursts: every frame recovered but a lost ODOMETRY, which is silent") {
  const LinkRun& clean = clean_run();
  auto line = std::make_shared<FaultLine>(parse_link_faults("ber=1e-4,drop=0.5,burst=0.1,seed=7"));
  const std::unique_ptr<LinkRun> faulty = run_link(line, 0xFA18);
  const FaultCounts& c = line->counts;
  CHECK(faulty->result.scans == clean.result.scans);
  CHECK(faulty->replies.size() == clean.replies.size());

  // What never reached the device intact, in the run that was scored (after its last CONFIG).
  std::vector<std::uint16_t> lost_odometry;
  int lost_batches = 0, lost_controls = 0;
  for (const auto& [seq, type] : faulty->sent.type) {
    if (faulty->arrived.type.count(seq) != 0) continue;
    if (type == static_cast<std::uint8_t>(proto::MsgType::kObsBatch)) {
      ++lost_batches;
    } else if (type == static_cast<std::uint8_t>(proto::MsgType::kOdometry)) {
      if (static_cast<std::int16_t>(static_cast<std::uint16_t>(seq - faulty->sent.last_config)) > 0)
        lost_odometry.push_back(seq);
    } else {
      ++lost_controls;  // HELLO, STATS_REQUEST, CONFIG, RESET: asked again with a new seq
    }
  }
  CHECK(lost_batches == 0);  // every OBS_BATCH arrived (resent with its seq)
  const std::vector<std::uint32_t> differ = differing(clean, *faulty);
  std::ostringstream m;
  m << summary(*faulty, c) << "\nframes that never arrived: " << lost_odometry.size() << " ODOMETRY, " << lost_controls
    << " control (retried)\nreplies that differ from the clean run's: " << differ.size();
  if (!lost_odometry.empty()) {
    // The first batch sent after the first lost ODOMETRY: its reply is the first to differ.
    std::uint32_t first_after = 0;
    bool found = false;
    for (const auto& [seq, id] : faulty->sent.batch) {
      if (static_cast<std::int16_t>(static_cast<std::uint16_t>(seq - lost_odometry.front())) > 0 &&
          static_cast<std::int16_t>(static_cast<std::uint16_t>(seq - faulty->sent.last_config)) > 0) {
        first_after = id;
        found = true;
        break;
      }
    }
    m << " (the first lost ODOMETRY is seq " << lost_odometry.front() << ", before batch " << first_after << ")";
    REQUIRE(found);
    REQUIRE_FALSE(differ.empty());
    CHECK(differ.front() == first_after);
  } else {
    CHECK(differ.empty());
  }
  MESSAGE(m.str());
  CHECK(c.to_device.events() > 0);
  CHECK(c.from_device.events() > 0);
  CHECK(rejected(faulty->host) > 0);
  CHECK(faulty->device.bad_crc + faulty->device.bad_length + faulty->device.overrun > 0);
  CHECK(faulty->reconnections + faulty->restarts > 0);
}
