// The serial link end to end on a pseudo-terminal: the device loop (node::Node in float) serves the
// pty's master in a thread, the host's LinkClient talks to the slave through the termios transport,
// and a whole scenario is streamed. Every association and pose must equal, bit for bit, the
// in-process SLAM step in float fed with the same decoded inputs.
#include <doctest/doctest.h>

#include <atomic>
#include <cstring>
#include <thread>

#include "geojcbb/node/node.hpp"
#include "geojcbb_host/stream.hpp"
#include "support/pty_device.hpp"
#include "support/reply_check.hpp"

using namespace geojcbb;
using namespace geojcbb::host;

namespace {
using Device = geojcbb::test::PtyDevice;
}  // namespace

TEST_CASE("loopback: a whole env1 run over a pty equals the in-process float pipeline, bit for bit") {
  Scenario sc = load_scenario(std::string(GEOJCBB_SCENARIO_DIR) + "/env1.json");
  Device dev(0xB007);
  PosixSerial port(dev.pty.slave_path());
  LinkClient link(port);
  const proto::Capabilities caps = link.hello();
  CHECK(caps.boot_id == 0xB007u);
  CHECK(caps.max_observations == DesktopBounds::kMaxObservations);
  CHECK(caps.scalar_bytes == 4);
  CHECK(caps.schema_hash == proto::kSchemaHash);

  for (Strategy s : {Strategy::kGeojcbb, Strategy::kJcbb}) {
    CAPTURE(to_string(s));
    RunOptions o;
    o.step.strategy = s;
    o.max_steps = 0;  // the whole lap: 737 scans
    // The reference: the same messages, decoded the same way, run in this process.
    auto ref = std::make_unique<node::SlamStep<float, DesktopBounds>>();
    REQUIRE(ref->configure(node::settings_from<float, DesktopBounds>(link_config(sc, o))) == Status::kOk);
    Pose2<float> x0;
    Mat3<float> P0;
    node::reset_from(link_reset(sc), x0, P0);
    REQUIRE(ref->reset(x0, P0) == Status::kOk);
    auto obs = std::make_unique<Observations<float, DesktopBounds>>();
    auto res = std::make_unique<node::StepResult<float, DesktopBounds>>();
    // The odometry reaches the reference through the hook's ordering: replay the same simulator.
    Simulator sim(sc, 3);
    SimStep step;
    long mismatches = 0, scans = 0, pairs = 0;
    auto hook = [&](const LinkObsBatch& b, const LinkClient::ScanReply& r) {
      // Advance the reference to this scan with the same odometry the device received.
      while (sim.step(step)) {
        REQUIRE(ref->predict(node::odometry_from<float>(link_odometry(sc, step))) == Status::kOk);
        if (step.scan) break;
      }
      REQUIRE(node::observations_from(b, *obs) == Status::kOk);
      REQUIRE(ref->step(*obs, *res) == Status::kOk);
      ++scans;
      const test::ReplyCheck c = test::check_reply(r, *res, ref->slam());
      mismatches += c.mismatches;
      pairs += c.paired;
    };
    const RunResult run = stream_scenario(link, sc, 3, o, hook);
    CHECK(scans == 737);
    CHECK(run.scans == 737);
    CHECK(pairs > 3000);
    CHECK(mismatches == 0);
    CHECK(run.score.f1() > 0.98);
  }
  const proto::Stats st = link.stats();
  CHECK(st.scans == 2 * 737);
  CHECK(st.bad_crc == 0);
  CHECK(st.bad_length == 0);
  CHECK(st.invalid_field == 0);
}

TEST_CASE("loopback: the device refuses work before the handshake and a wrong schema") {
  Device dev(7);
  PosixSerial port(dev.pty.slave_path());
  LinkClient link(port, 1000);
  CHECK_THROWS_WITH_AS(link.configure(proto::Config{}), doctest::Contains("not-ready"), LinkError);
  link.hello();
  // The client refuses to send an invalid CONFIG ...
  proto::Config bad;
  bad.local_radius_m = -1.0f;
  CHECK_THROWS_WITH_AS(link.configure(bad), doctest::Contains("out-of-range"), LinkError);
  // ... so write one by hand (radius at payload offset 9): the device answers ERROR, counts it,
  // and changes nothing.
  std::uint8_t payload[proto::Config::kMaxPayloadSize];
  std::size_t n = 0;
  REQUIRE(proto::Config{}.encode(payload, sizeof payload, n) == proto::Error::kOk);
  const float minus_one = -1.0f;
  std::memcpy(payload + 9, &minus_one, 4);  // little-endian host
  proto::EncodedFrame f;
  REQUIRE(proto::encode_frame(static_cast<std::uint8_t>(proto::MsgType::kConfig), 77, 0, payload, n, f.bytes.data(),
                              f.bytes.size(), f.size) == proto::Error::kOk);
  port.write(f.bytes.data(), f.size);
  CHECK_THROWS_WITH_AS(link.stats(), doctest::Contains("seq 77: out-of-range"), LinkError);
  // The answer to that request was queued behind the ERROR; a PING's wait reads past it and keeps
  // it as the latest STATS: it counts CONFIG before HELLO, HELLO, the bad CONFIG and the request.
  link.ping(1);
  REQUIRE(link.last_stats().has_value());
  CHECK(link.last_stats()->invalid_field == 1);
  CHECK(link.last_stats()->frames_ok == 4);
  const proto::Stats st = link.stats();  // a fresh answer: the PING and this request too
  CHECK(st.invalid_field == 1);
  CHECK(st.frames_ok == 6);
}

TEST_CASE("loopback: periodic STATS reach last_stats() between replies, and SHUTDOWN ends serving with its code") {
  Scenario sc = load_scenario(std::string(GEOJCBB_SCENARIO_DIR) + "/env1.json");
  Pty pty;
  std::atomic<bool> stop{false};
  ServeResult served;
  std::thread device([&] { served = serve_device(pty, stop, 0x5EED); });
  {
    PosixSerial port(pty.slave_path());
    LinkClient link(port, 2000);
    CHECK_THROWS_WITH_AS(link.shutdown(3), doctest::Contains("not-ready"), LinkError);  // not before HELLO
    link.hello();
    CHECK_FALSE(link.last_stats().has_value());
    proto::Config c = link_config(sc, RunOptions{});
    c.stats_period_scans = 10;
    link.configure(c);
    link.reset(link_reset(sc));
    Simulator sim(sc, 1);
    SimStep step;
    std::vector<int> kept;
    std::uint32_t batch = 0;
    while (batch < 35 && sim.step(step)) {
      link.odometry(link_odometry(sc, step));
      if (!step.scan) continue;
      const LinkClient::ScanReply r = link.scan(link_batch(step.observations, batch, kept));
      CHECK(r.result.batch_id == batch);
      ++batch;
    }
    // STATS after scans 10, 20 and 30; the last is read while waiting for scan 31's reply.
    CHECK(link.stats_received() == 3);
    REQUIRE(link.last_stats().has_value());
    CHECK(link.last_stats()->scans == 30);
    CHECK(link.stats().scans == 35);
    CHECK(link.last_stats()->scans == 35);
    link.ping(0xABCD);
    link.shutdown(7);
  }
  device.join();  // the device stopped by itself
  REQUIRE(served.shutdown_code.has_value());
  CHECK(*served.shutdown_code == 7);
}
