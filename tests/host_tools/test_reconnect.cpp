// Reconnection and re-handshake (LinkSession): the desktop device serves a pty in a thread, and in
// the middle of a stream the device restarts with a new boot id (the run starts again from the
// beginning, with a note), or its port closes and a new one opens (same boot id: the pending frames
// are resent and the stream goes on), or a reply arrives late, after its retransmission (the
// duplicate is skipped, never scored twice). Every disturbed run scores exactly as an undisturbed one.
#include <doctest/doctest.h>

#include <atomic>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "geojcbb_host/session.hpp"

using namespace geojcbb;
using namespace geojcbb::host;

namespace {

/// The desktop device on a pty, served by a thread; it can restart (new state, new boot id) and
/// move to a new pty (same state; the old port closes).
class TestDevice {
 public:
  explicit TestDevice(std::uint32_t boot_id)
      : pty_(std::make_unique<Pty>()), dev_(std::make_unique<DesktopDevice>(boot_id)) {
    path_ = pty_->slave_path();
    start();
  }
  ~TestDevice() { halt(); }
  std::string path() {
    std::lock_guard<std::mutex> lock(mu_);
    return path_;
  }
  void restart(std::uint32_t boot_id) {
    halt();
    dev_ = std::make_unique<DesktopDevice>(boot_id);
    start();
  }
  void reopen_port() {
    halt();
    {
      std::lock_guard<std::mutex> lock(mu_);
      pty_.reset();  // the host's end of the old port sees it close
      pty_ = std::make_unique<Pty>();
      path_ = pty_->slave_path();
    }
    start();
  }

 private:
  void start() {
    stop_ = false;
    thread_ = std::thread([this] {
      try {
        dev_->serve(*pty_, stop_);
      } catch (const std::exception&) {
      }
    });
  }
  void halt() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  std::mutex mu_;
  std::unique_ptr<Pty> pty_;
  std::string path_;
  std::unique_ptr<DesktopDevice> dev_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

/// A line that can hold back what the device sends, from the k-th OBS_BATCH on, until that batch is
/// sent again (its retransmission after a reconnection): the reply then arrives late, before the
/// device's second copy of it.
struct Line {
  int hold_at = -1;  ///< OBS_BATCH write that starts holding (1-based), -1: never
  int batches = 0;
  bool holding = false, released = false;
  std::vector<std::uint8_t> held, held_frame;
};

class HoldingPort : public Transport {
 public:
  HoldingPort(const std::string& path, Line& line) : inner_(path), line_(line) { line_.holding = false; }
  std::size_t read(std::uint8_t* p, std::size_t n, int timeout_ms) override {
    if (line_.released && !line_.held.empty()) {
      const std::size_t k = std::min(n, line_.held.size());
      std::copy(line_.held.begin(), line_.held.begin() + static_cast<std::ptrdiff_t>(k), p);
      line_.held.erase(line_.held.begin(), line_.held.begin() + static_cast<std::ptrdiff_t>(k));
      return k;
    }
    const std::size_t got = inner_.read(p, n, timeout_ms);
    if (!line_.holding) return got;
    line_.held.insert(line_.held.end(), p, p + got);
    return 0;
  }
  void write(const std::uint8_t* p, std::size_t n) override {
    const std::vector<std::uint8_t> bytes(p, p + n);
    proto::Decoder d;
    proto::FrameView f;
    std::size_t used = 0;
    if (n > 1 && d.push(p, n, f, used) == proto::Error::kOk &&
        f.type == static_cast<std::uint8_t>(proto::MsgType::kObsBatch)) {
      if (!line_.held_frame.empty() && bytes == line_.held_frame) {
        line_.released = true;  // the retransmission: the held reply comes first
      } else if (++line_.batches == line_.hold_at) {
        line_.holding = true;
        line_.held_frame = bytes;
      }
    }
    inner_.write(p, n);
  }

 private:
  PosixSerial inner_;
  Line& line_;
};

struct Run {
  RunResult result;
  std::vector<std::string> notes;
  int restarts = 0, reconnections = 0;
  std::uint64_t duplicates = 0;
};

/// Streams env1 (seed 3, the whole lap) through `dev`; `disturb(scan)` runs after each scored scan.
Run stream(TestDevice& dev, int window, const std::function<void(int)>& disturb, Line* line = nullptr,
           int max_restarts = 3) {
  static const Scenario sc = load_scenario(std::string(GEOJCBB_SCENARIO_DIR) + "/env1.json");
  Run out;
  SessionOptions so;
  so.open = [&]() -> std::unique_ptr<Transport> {
    if (line != nullptr) return std::make_unique<HoldingPort>(dev.path(), *line);
    return std::make_unique<PosixSerial>(dev.path());
  };
  so.timeout_ms = 400;
  so.reconnect_ms = 5000;
  so.max_restarts = max_restarts;
  so.note = [&](const std::string& s) { out.notes.push_back(s); };
  LinkSession session(so);
  SimSource src(sc, 3);
  RunOptions o;
  o.step.strategy = Strategy::kGeojcbb;
  StreamOptions st;
  st.window = window;
  int scans = 0;
  st.hook = [&](const LinkObsBatch&, const LinkClient::ScanReply&) {
    if (disturb) disturb(++scans);
  };
  out.result = stream_run(session, src, o, st);
  out.restarts = session.restarts();
  out.reconnections = session.reconnections();
  out.duplicates = session.client().duplicate_replies();
  return out;
}

void check_same(const RunResult& a, const RunResult& b) {
  CHECK(a.scans == b.scans);
  CHECK(a.observations == b.observations);
  CHECK(a.score.tp == b.score.tp);
  CHECK(a.score.tn == b.score.tn);
  CHECK(a.score.fp == b.score.fp);
  CHECK(a.score.fn == b.score.fn);
  CHECK(a.landmarks == b.landmarks);
  CHECK(a.mean_abs_x_m == b.mean_abs_x_m);
  CHECK(a.mean_abs_y_m == b.mean_abs_y_m);
  REQUIRE(a.steps.size() == b.steps.size());
  for (std::size_t k = 0; k < a.steps.size(); ++k) CHECK(a.steps[k].pose_nees == b.steps[k].pose_nees);
}

bool has_note(const Run& r, const std::string& text) {
  for (const std::string& n : r.notes)
    if (n.find(text) != std::string::npos) return true;
  return false;
}

}  // namespace

TEST_CASE("reconnect: the device restarts mid-stream: handshake again, say so, the run starts over, same scores") {
  for (const int window : {1, 4}) {
    CAPTURE(window);
    TestDevice ref_dev(0x100);
    const Run ref = stream(ref_dev, window, nullptr);
    CHECK(ref.result.scans == 737);
    CHECK(ref.restarts == 0);
    CHECK(ref.reconnections == 0);

    TestDevice dev(0x200);
    bool done = false;
    const Run r = stream(dev, window, [&](int scan) {
      if (scan == 300 && !done) {
        done = true;
        dev.restart(0x300);  // state gone, new boot id
      }
    });
    CHECK(r.restarts == 1);
    CHECK(has_note(r, "the device restarted (boot id 00000200 -> 00000300)"));
    CHECK(has_note(r, "the run starts again from the beginning (restart 1 of at most 3)"));
    check_same(r.result, ref.result);
  }
}

TEST_CASE("reconnect: the port closes and another opens (same device): pending frames resent, the stream goes on") {
  TestDevice ref_dev(0x100);
  const Run ref = stream(ref_dev, 1, nullptr);
  TestDevice dev(0x200);
  const Run r = stream(dev, 1, [&](int scan) {
    if (scan == 250 || scan == 500) dev.reopen_port();
  });
  CHECK(r.reconnections == 2);
  CHECK(r.restarts == 0);  // the device kept its state: no restart
  CHECK(has_note(r, "reconnected to the same device (boot id 00000200)"));
  check_same(r.result, ref.result);
  // With batches in flight, replies the closing port swallowed may be lost for good; then the run
  // starts over. Either way the scores are the undisturbed run's.
  TestDevice dev4(0x400);
  const Run r4 = stream(dev4, 4, [&](int scan) {
    if (scan == 250) dev4.reopen_port();
  });
  CHECK(r4.reconnections >= 1);
  std::string notes;
  for (const std::string& n : r4.notes) notes += "\n  " + n;
  MESSAGE("window 4, port reopened at scan 250: " << r4.reconnections << " reconnection(s), " << r4.restarts
                                                  << " restart(s):" << notes);
  check_same(r4.result, ref.result);
}

TEST_CASE("reconnect: a reply that times out and arrives after its retransmission is scored once") {
  TestDevice ref_dev(0x100);
  const Run ref = stream(ref_dev, 1, nullptr);
  TestDevice dev(0x200);
  Line line;
  line.hold_at = 123;
  const Run r = stream(dev, 1, nullptr, &line);
  CHECK(line.released);
  CHECK(r.reconnections == 1);
  CHECK(r.restarts == 0);
  CHECK(r.duplicates == 1);  // the late original came first; the device's second copy was skipped
  CHECK(has_note(r, "timeout waiting for the reply to batch 122"));
  std::string notes;
  for (const std::string& n : r.notes) notes += "\n  " + n;
  MESSAGE("late reply:" << notes);
  check_same(r.result, ref.result);
}

TEST_CASE("reconnect: more restarts than allowed fail clearly") {
  TestDevice dev(0x200);
  std::uint32_t boot = 0x300;
  CHECK_THROWS_WITH_AS(stream(
                           dev, 1,
                           [&](int scan) {
                             if (scan % 100 == 0) dev.restart(boot++);  // every attempt is cut short
                           },
                           nullptr, 2),
                       doctest::Contains("giving up: the device restarted, and this run was started again 2 times"),
                       LinkError);
}
