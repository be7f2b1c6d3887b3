// node: the device loop. Portable, no OS: the board feeds received bytes to on_bytes() and supplies
// a write function; the Node decodes frames (protocol/), runs the handshake, CONFIG and RESET, and for
// each ODOMETRY + OBS_BATCH predicts, associates with the configured strategy, updates, augments and
// answers ASSOC_RESULT and POSE. STATS on request and periodically. The same code runs in a desktop
// process (over a pseudo-terminal) and on the Cortex-M4F (over the UART).
//   before HELLO:   only HELLO and PING are served; anything else gets ERROR kNotReady
//   HELLO           version and schema hash checked: CAPABILITIES, or NACK
//   CONFIG, RESET   ACK, or NACK with the reason (nothing changes)
//   SHUTDOWN        ACK, then the board's shutdown hook (Output::shutdown) with the exit code
//   ODOMETRY        predict (needs CONFIG and RESET first)
//   ODOM_DELTA      predict with a pose increment and its covariance (instead of ODOMETRY)
//   OBS_BATCH       one SLAM step: ASSOC_RESULT then POSE, or ERROR (nothing changes); then STATS
//                   when CONFIG's stats_period_scans is N > 0 and this is the N-th scan since the last
//   hand-over       a scan that closes the local map (CONFIG's submap_* rule) has POSE.submap_frames
//                   > 0: SUBMAP and SUBMAP_COV frames follow, read in place from the filter (no copy);
//                   until SUBMAP_ACK every stream frame gets ERROR kBusy and is not applied (the host
//                   sends it again). SUBMAP_ACK: ACK, then the next map (SlamStep::restart); with
//                   send, ACK and the same map again (or the current map, closed now: the end of a
//                   run). RESET and CONFIG drop a pending map; a HELLO (a reconnection) keeps it.
//                   SUBMAP_SEED seeds the local map. Defined in node/hand_over.hpp.
//   retransmission  a stream frame (ODOMETRY, OBS_BATCH) whose seq is not newer than the last applied
//                   one since CONFIG/RESET is not applied again; a repeated OBS_BATCH of the last
//                   applied batch id gets its stored ASSOC_RESULT and POSE again (a host that lost
//                   replies resends its pending frames with their original seq)
// Frames that fail the framing checks are counted by the decoder and not answered (their seq is not
// trustworthy); frames of unknown type or with invalid fields are counted and answered with ERROR.
// No heap: every buffer is a member, sized by the Bounds; the object is typically static.
#pragma once

#include <cstdint>
#include <cstddef>
#include <cstring>
#include <utility>

#include "geojcbb/node/slam_step.hpp"
#include "geojcbb/node/wire.hpp"
#include "geojcbb/protocol/protocol.hpp"

namespace geojcbb::node {

/// The board's output: writes n bytes (blocking or buffered; the Node does not retry), and an
/// optional shutdown hook, called after the ACK of a SHUTDOWN has been written (nullptr: SHUTDOWN is
/// only acknowledged). Both get `context`.
struct Output {
  void* context = nullptr;
  void (*write)(void* context, const std::uint8_t* data, std::size_t n) = nullptr;
  void (*shutdown)(void* context, std::uint8_t exit_code) = nullptr;
};

template <typename T, class B>
class Node {
 public:
  using ObsBatch = proto::ObsBatchT<static_cast<std::size_t>(B::kMaxObservations)>;
  using AssocResult = proto::AssocResultT<static_cast<std::size_t>(B::kMaxObservations)>;

  /// @param boot_id  changes at every boot, so a host notices a reset
  /// @param clock    stage counter for STATS (nullptr: zeros)
  void start(Output out, std::uint32_t boot_id, CounterFn clock = nullptr) {
    out_ = out;
    boot_id_ = boot_id;
    clock_ = clock;
    hello_ = configured_ = reset_ = false;
    new_run();
  }

  /// Feeds received bytes.  Bound: n bytes, each O(1) except a frame's end (one message).
  void on_bytes(const std::uint8_t* p, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) {  // <= n
      proto::FrameView f;
      if (decoder_.push(p[i], f) == proto::Error::kOk) handle(f);
    }
  }

  /// The counters STATS reports.
  proto::Stats stats() const {
    proto::Stats s;
    const proto::DecoderCounters& d = decoder_.counters();
    s.frames_ok = d.frames_ok;
    s.bad_crc = d.bad_crc;
    s.bad_length = d.bad_length;
    s.overrun = d.overrun;
    s.bad_version = d.bad_version;
    s.bad_flags = d.bad_flags;
    s.unknown_type = msg_counters_.unknown_type;
    s.invalid_field = msg_counters_.invalid_field;
    s.budget_hits = budget_hits_;
    s.ambiguous_scans = ambiguous_scans_;
    s.movers = movers_;
    s.scans = scans_;
    s.instr_predict = last_predict_;
#define GEOJCBB_STAGE_COUNT_COPY(name, meaning) s.instr_##name = last_.counts.name;
    GEOJCBB_STAGE_COUNTS(GEOJCBB_STAGE_COUNT_COPY)
#undef GEOJCBB_STAGE_COUNT_COPY
    s.stack_high_water_bytes = stack_high_water_;
    return s;
  }
  void set_stack_high_water(std::uint32_t bytes) { stack_high_water_ = bytes; }
  const SlamStep<T, B>& slam_step() const { return step_; }

 private:
  // Decodes a frame's payload into `m` and validates it, in place (decode() would copy through a
  // temporary): large messages are read into a member scratch, so the stack stays small and a
  // rejected payload is simply not used.
  template <class M>
  static proto::Error take(const proto::FrameView& f, M& m) {
    return m.decode_in_place(f.payload, f.len);
  }
  template <class M>
  proto::Error serve(const proto::FrameView& f) {
    M m{};
    const proto::Error e = take(f, m);
    if (e == proto::Error::kOk) on_message(m);
    return e;
  }

  /// SUBMAP_SEED decoded out of line: its 204 B stay out of handle()'s frame, which is on the
  /// deepest call chain (the lost scan's alignment; docs/firmware.md, "Stack").
  [[gnu::noinline, gnu::cold]] proto::Error serve_seed(const proto::FrameView& f);

  void handle(const proto::FrameView& f) {
    rx_type_ = f.type;
    rx_seq_ = f.seq;
    follow_seq();
    proto::Error e = proto::Error::kOk;
    switch (static_cast<proto::MsgType>(f.type)) {
      case proto::MsgType::kHello: e = serve<proto::Hello>(f); break;
      case proto::MsgType::kPing: e = serve<proto::Ping>(f); break;
      case proto::MsgType::kConfig:  // decoded into members: CONFIG and the settings are too large for a frame
        e = take(f, rx_config_);
        if (e == proto::Error::kOk) on_message(rx_config_);
        break;
      case proto::MsgType::kReset: e = serve<proto::Reset>(f); break;
      case proto::MsgType::kRelocalise: e = serve<proto::Relocalise>(f); break;
      case proto::MsgType::kSubmapAck:  // a device without the hand-over does not take it
        if constexpr (OptionalStages<B>::kHandOver) {
          e = serve<proto::SubmapAck>(f);
        } else {
          e = proto::Error::kUnknownType;
        }
        break;
      case proto::MsgType::kSubmapSeed:  // the local maps' seed, with the hand-over
        if constexpr (OptionalStages<B>::kHandOver) {
          e = serve_seed(f);
        } else {
          e = proto::Error::kUnknownType;
        }
        break;
      case proto::MsgType::kShutdown: e = serve<proto::Shutdown>(f); break;
      case proto::MsgType::kOdometry: e = serve<proto::Odometry>(f); break;
      case proto::MsgType::kOdomDelta: e = serve<proto::OdomDelta>(f); break;
      case proto::MsgType::kStatsRequest: e = serve<proto::StatsRequest>(f); break;
      case proto::MsgType::kObsBatch:
        e = take(f, rx_batch_);
        if (e == proto::Error::kOk) on_message(rx_batch_);
        break;
      default: e = proto::Error::kUnknownType; break;  // unknown, or a type a device does not take
    }
    if (e != proto::Error::kOk) {
      msg_counters_.record(e);
      error(e);
    }
  }

  void on_message(const proto::Hello& m) {
    const proto::Error e = proto::check_hello(m);
    if (e != proto::Error::kOk) {
      nack(e);
      return;
    }
    hello_ = true;
    proto::Capabilities c;
    c.max_observations = static_cast<std::uint16_t>(B::kMaxObservations);
    c.max_candidates = static_cast<std::uint16_t>(B::kMaxCandidates);
    c.max_groups = static_cast<std::uint8_t>(B::kMaxGroups);
    c.max_landmarks = static_cast<std::uint16_t>(B::kMaxLandmarks);
    c.max_jcbb_nodes = B::kMaxJcbbNodes;
    c.scalar_bytes = static_cast<std::uint8_t>(sizeof(T));
    c.boot_id = boot_id_;
    constexpr char kId[] = "geojcbb node";
    static_assert(sizeof(kId) - 1 <= sizeof(c.firmware_id), "the id fits CAPABILITIES' field");
    for (std::size_t i = 0; i < sizeof(kId) - 1; ++i) c.firmware_id[i] = kId[i];  // <= 16
    send(c);
  }

  void on_message(const proto::Ping& m) {
    proto::Pong p;
    p.nonce = m.nonce;
    send(p);
  }

  [[gnu::cold]] void on_message(const proto::Config& m) {
    if (!ready()) return;
    settings_ = kDefaultSettings;  // an option CONFIG does not carry keeps its default
    config_wire::settings_from(m, settings_, std::make_index_sequence<config_wire::kFieldCount>{});
    const Status st = step_.configure(settings_);
    if (st != Status::kOk) {
      nack(st == Status::kInvalidInput ? proto::Error::kOutOfRange : proto::Error::kInternal);
      return;
    }
    configured_ = true;
    stats_period_ = m.stats_period_scans;
    new_run();
    ack();
  }

  void on_message(const proto::Reset& m) {
    if (!ready()) return;
    Pose2<T> x0;
    Mat3<T> P;
    reset_from(m, x0, P);
    const Status st = step_.reset(x0, P);
    if (st != Status::kOk) {
      nack(proto::Error::kNotPositiveDefinite);
      return;
    }
    reset_ = true;
    new_run();
    ack();
  }

  void on_message(const proto::Relocalise& m) {
    if (!running() || !fresh() || busy()) return;  // a retransmitted RELOCALISE was applied already
    const auto& u = m.cov_upper;
    Mat3<T> P;
    P << T(u[0]), T(u[1]), T(u[2]), T(u[1]), T(u[3]), T(u[4]), T(u[2]), T(u[4]), T(u[5]);
    if (step_.relocalise(step_.slam().pose(), P) != Status::kOk) {
      invalid();
      return;
    }
    step_.lost();
    applied();
  }

  void on_message(const proto::Shutdown& m) {
    if (!ready()) return;
    ack();
    if (out_.shutdown != nullptr) out_.shutdown(out_.context, m.exit_code);
  }

  void on_message(const proto::Odometry& m) {
    if (!running() || !fresh() || busy()) return;  // a retransmitted ODOMETRY was applied already
    const std::uint32_t t0 = clock_ ? clock_() : 0;
    const Status st = step_.predict(odometry_from<T>(m));
    last_predict_ = clock_ ? clock_() - t0 : 0;
    if (st != Status::kOk) {
      invalid();
      return;
    }
    applied();
  }

  /// Out of line: its increment and covariance stay out of handle()'s frame (the call chain's
  /// budget, docs/firmware.md).
  [[gnu::noinline]] void on_message(const proto::OdomDelta& m) {
    if (!running() || !fresh() || busy()) return;  // a retransmitted ODOM_DELTA was applied already
    const std::uint32_t t0 = clock_ ? clock_() : 0;
    const auto& u = m.cov_upper;
    ekf::PoseIncrement<T> d{T(m.dx_m), T(m.dy_m), T(m.dtheta_rad), Mat3<T>::Zero()};
    d.cov << T(u[0]), T(u[1]), T(u[2]), T(u[1]), T(u[3]), T(u[4]), T(u[2]), T(u[4]), T(u[5]);
    const Status st = step_.predict(d);
    last_predict_ = clock_ ? clock_() - t0 : 0;
    if (st != Status::kOk) {
      invalid();
      return;
    }
    applied();
  }

  void on_message(const ObsBatch& m) {
    if (!running()) return;
    if (!fresh()) {  // retransmitted: never stepped twice; the last batch's replies are sent again
      if (have_result_ && m.batch_id == result_.batch_id) {
        send(result_);
        send(pose_);
      }
      return;
    }
    if (busy()) return;
    if (observations_from(m, obs_) != Status::kOk) {
      invalid();
      return;
    }
    if (step_.step(obs_, last_, clock_) != Status::kOk) {
      invalid();
      return;
    }
    ++scans_;
    budget_hits_ += last_.diag.node_budget_hit ? 1u : 0u;
    ambiguous_scans_ += last_.reloc.ambiguous || last_.loop.ambiguous ? 1u : 0u;
    movers_ += static_cast<std::uint32_t>(last_.review.movers);
    to_wire(last_, m.batch_id, result_);
    send(result_);
    applied();
    have_result_ = true;
    handing_over_ = last_.submap_due;
    to_wire(step_.slam(), m.batch_id, handing_over_, pose_);
    send(pose_);
    if (stats_period_ != 0 && ++since_stats_ >= stats_period_) {
      since_stats_ = 0;
      send(stats());
    }
    if constexpr (OptionalStages<B>::kHandOver) {
      if (handing_over_) send_submap();
    }
  }

  // The local map's hand-over (SUBMAP_SEED, SUBMAP_ACK, the SUBMAP and SUBMAP_COV frames), defined
  // in node/hand_over.hpp.
  /// Out of line and cold: its seeds (224 B) stay out of handle()'s frame; the answers are a member
  /// (96 B), which keeps this frame within the 512-B limit (docs/firmware.md).
  [[gnu::cold, gnu::noinline]] void on_message(const proto::SubmapSeed& m);

  /// SUBMAP_ACK: the closed map acknowledged (the next map begins), or asked for again.
  [[gnu::cold]] void on_message(const proto::SubmapAck& m);

  /// The closed map as SUBMAP then SUBMAP_COV frames, read from the filter in place. Two functions out
  /// of line: each frame's message is on the stack of its own (within the 512-byte frame limit), out
  /// of handle()'s frame (docs/firmware.md).
  /// Bound: n / 16 + 1 + D (D + 1) / 192 + 1 frames for n landmarks, D = 3 + 2 n.
  [[gnu::cold]] void send_submap();
  /// The SUBMAP frames (chunks 0 ...); returns the next chunk's index.
  [[gnu::noinline, gnu::cold]] std::uint16_t send_submap_landmarks(std::uint16_t frames);
  /// The SUBMAP_COV frames from chunk `chunk` on: the upper triangle, column by column.
  [[gnu::noinline, gnu::cold]] void send_submap_cov(std::uint16_t chunk, std::uint16_t frames);
  /// send(), in a frame of its own: the encoder's frame and the message's do not add up in one.
  template <class M>
  [[gnu::noinline, gnu::cold]] void send_out_of_line(const M& m);

  void on_message(const proto::StatsRequest&) { send(stats()); }

  // A new run (start, CONFIG, RESET): stream sequence numbers and the periodic STATS count restart.
  void new_run() {
    have_stream_seq_ = have_result_ = handing_over_ = have_handed_ = false;
    since_stats_ = 0;
    map_id_ = 0;
  }
  // A stream frame during a hand-over: not applied (its seq not taken), ERROR kBusy.
  bool busy() {
    if (!handing_over_) return false;
    error(proto::Error::kBusy);
    return true;
  }
  // True when the current stream frame is newer than the last applied one (serial numbers, RFC 1982:
  // a retransmission carries its original seq, never newer).
  bool fresh() const {
    return !have_stream_seq_ || static_cast<std::int16_t>(static_cast<std::uint16_t>(rx_seq_ - last_stream_seq_)) > 0;
  }
  void applied() {
    last_stream_seq_ = rx_seq_;
    have_stream_seq_ = true;
  }
  // Control frames (PING, STATS_REQUEST, ...) advance the host's seq too. Without this, 32,768 of
  // them between two stream frames would make every later stream frame look old (serial arithmetic
  // wraps) and the device would answer nothing. The reference follows any frame to at most
  // kRetransmitWindow behind it: a retransmission is recognised if it is at most that old.
  void follow_seq() {
    if (!have_stream_seq_) return;
    const std::uint16_t behind = static_cast<std::uint16_t>(rx_seq_ - last_stream_seq_);
    if (static_cast<std::int16_t>(behind) > static_cast<std::int16_t>(proto::kRetransmitWindow)) {
      last_stream_seq_ = static_cast<std::uint16_t>(rx_seq_ - proto::kRetransmitWindow);
    }
  }
  bool ready() {
    if (hello_) return true;
    error(proto::Error::kNotReady);
    return false;
  }
  bool running() {
    if (hello_ && configured_ && reset_) return true;
    error(proto::Error::kNotReady);
    return false;
  }
  void invalid() {
    msg_counters_.record(proto::Error::kOutOfRange);
    error(proto::Error::kOutOfRange);
  }
  void ack() {
    proto::Ack a;
    a.acked_type = rx_type_;
    a.acked_seq = rx_seq_;
    send(a);
  }
  void nack(proto::Error e) {
    proto::Nack n;
    n.nacked_type = rx_type_;
    n.nacked_seq = rx_seq_;
    n.error = e;
    send(n);
  }
  void error(proto::Error e) {
    if (!proto::is_reportable(e)) e = proto::Error::kInternal;
    proto::ErrorReport r;
    r.error = e;
    r.offending_type = rx_type_;
    r.offending_seq = rx_seq_;
    send(r);
  }
  template <class M>
  void send(const M& m) {
    if (proto::encode_message(m, tx_seq_++, 0, frame_) == proto::Error::kOk && out_.write != nullptr) {
      out_.write(out_.context, frame_.bytes.data(), frame_.size);
    }
  }

  SlamStep<T, B> step_;
  Observations<T, B> obs_;
  StepResult<T, B> last_;
  ObsBatch rx_batch_;
  static constexpr StepSettings<T> kDefaultSettings{};
  proto::Config rx_config_;
  StepSettings<T> settings_;               ///< CONFIG's settings, built here rather than on the stack
  AssocResult result_;                     ///< the last batch's, kept for a retransmitted OBS_BATCH
  proto::Pose pose_;                       ///< likewise
  SeedAnswer<T> seed_answers_[kMaxSeeds];  ///< SUBMAP_SEED's answers, before they go into result_
  proto::Decoder decoder_;
  proto::MessageCounters msg_counters_;
  proto::EncodedFrame frame_;
  Output out_;
  CounterFn clock_ = nullptr;
  std::uint32_t map_id_ = 0;  ///< the current local map's number since CONFIG or RESET
  std::uint32_t boot_id_ = 0, scans_ = 0, budget_hits_ = 0, ambiguous_scans_ = 0, movers_ = 0, last_predict_ = 0,
                stack_high_water_ = 0;
  std::uint16_t tx_seq_ = 0, rx_seq_ = 0, last_stream_seq_ = 0, stats_period_ = 0, since_stats_ = 0;
  std::uint8_t rx_type_ = 0;
  bool hello_ = false, configured_ = false, reset_ = false, have_stream_seq_ = false, have_result_ = false;
  bool handing_over_ = false;  ///< the closed map waits for SUBMAP_ACK (stream frames: kBusy)
  bool have_handed_ = false;   ///< a map was acknowledged since CONFIG or RESET (map_id_ - 1)
};

}  // namespace geojcbb::node

// The local map's hand-over (SUBMAP_SEED, SUBMAP_ACK, SUBMAP and SUBMAP_COV), defined in its own file.
#include "geojcbb/node/hand_over.hpp"  // IWYU pragma: export
