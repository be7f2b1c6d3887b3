// tests/fuzz: writes the seed corpus (tests/fuzz/corpus/): a valid frame of every message, a stream
// of several frames, truncated and bit-flipped frames, garbage, empty and oversize frames, and frames
// with a valid CRC but an invalid payload (bad version, unknown flags and type, NaN, count over
// capacity, len against count). Usage: protocol_make_corpus <output directory>. Deterministic; it
// overwrites its own files and leaves the fuzzer's additions (fuzz_*) alone.
#include <array>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "geojcbb/protocol/protocol.hpp"

namespace {

using namespace geojcbb::proto;
using Bytes = std::vector<std::uint8_t>;

std::filesystem::path g_dir;
int g_files = 0;

void save(const std::string& name, const Bytes& b) {
  std::ofstream out(g_dir / name, std::ios::binary);
  out.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
  ++g_files;
}

template <class M>
Bytes frame(const M& m, std::uint16_t seq = 1, std::uint8_t fl = 0) {
  EncodedFrame ef;
  if (encode_message(m, seq, fl, ef) != Error::kOk) {
    std::fprintf(stderr, "encode failed for %s\n", to_string(M::kType));
    std::exit(1);
  }
  return Bytes(ef.bytes.begin(), ef.bytes.begin() + static_cast<std::ptrdiff_t>(ef.size));
}

template <class M>
Bytes payload(const M& m) {
  std::array<std::uint8_t, M::kMaxPayloadSize> buf{};
  std::size_t n = 0;
  if (m.encode(buf.data(), buf.size(), n) != Error::kOk) std::exit(1);
  return Bytes(buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(n));
}

/// A frame with any header and payload and a valid CRC.
Bytes raw(std::uint8_t ver, std::uint8_t fl, std::uint8_t type, std::uint16_t len_field, const Bytes& pl) {
  Bytes f = {ver, fl, type, 0, 7, 0, 0, 0};
  put_u16_le(f.data() + 6, len_field);
  f.insert(f.end(), pl.begin(), pl.end());
  const std::uint32_t crc = crc32c(f.data(), f.size());
  f.resize(f.size() + 4);
  put_u32_le(f.data() + f.size() - 4, crc);
  Bytes out(cobs_max_encoded_size(f.size()) + 1);
  std::size_t n = 0;
  if (cobs_encode(f.data(), f.size(), out.data(), out.size(), n) != Error::kOk) std::exit(1);
  out.resize(n);
  out.push_back(0);
  return out;
}

ObsBatch batch(int count) {
  ObsBatch b{};
  b.batch_id = 1000u + static_cast<std::uint32_t>(count);
  b.count = static_cast<std::uint8_t>(count);
  for (int i = 0; i < count; ++i) {
    auto& o = b.obs[static_cast<std::size_t>(i)];
    o.range_m = 0.5f + 0.4f * static_cast<float>(i);
    o.bearing_rad = -2.5f + 0.23f * static_cast<float>(i);
    o.r00 = 0.01f;
    o.r01 = 0.0002f;
    o.r11 = 0.0009f;
  }
  return b;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s <output directory>\n", argv[0]);
    return 2;
  }
  g_dir = argv[1];
  std::filesystem::create_directories(g_dir);

  Capabilities caps{};
  caps.max_observations = 24;
  caps.max_candidates = 32;
  caps.max_groups = 5;
  caps.max_landmarks = 64;
  caps.max_jcbb_nodes = 4000;
  caps.boot_id = 0x1234;
  caps.set_firmware_id("geojcbb-0.1.0");
  Config cfg{};
  cfg.strategy = StrategyCode::kKjcbb;
  cfg.condition_groups = true;
  Ack ack{};
  ack.acked_type = static_cast<std::uint8_t>(MsgType::kReset);
  ack.acked_seq = 300;
  Nack nack{};
  nack.nacked_type = 3;
  nack.error = Error::kCapacityExceeded;
  Ping ping{};
  ping.nonce = 0xDEADBEEF;
  Pong pong{};
  pong.nonce = 0xDEADBEEF;
  Reset reset{};
  reset.x_m = 1.0f;
  reset.cov_upper = {0.1f, 0.01f, 0.0f, 0.1f, 0.0f, 0.01f};
  Shutdown shutdown{};
  shutdown.exit_code = 3;
  cfg.stats_period_scans = 10;
  Odometry odo{};
  odo.v_mps = 0.5f;
  odo.w_radps = 0.1f;
  odo.dt_s = 0.1f;
  odo.sigma_v_mps = 0.05f;
  odo.sigma_w_radps = 0.01f;
  AssocResult assoc{};
  assoc.batch_id = 1003;
  assoc.count = 3;
  assoc.pairs[0] = {PairingOutcome::kPaired, 4, 0.5f};
  assoc.pairs[1] = {PairingOutcome::kNewDropped, kFeatureNew, 30.0f};
  assoc.pairs[2] = {PairingOutcome::kUnmatched, kFeatureUnmatched, std::numeric_limits<float>::infinity()};
  Pose pose{};
  pose.batch_id = 1003;
  pose.x_m = 2.0f;
  pose.cov_upper = {0.2f, 0.0f, 0.0f, 0.2f, 0.0f, 0.05f};
  pose.landmark_count = 9;
  Stats stats{};
  stats.frames_ok = 5;
  stats.scans = 4;
  stats.instr_step = 100000;
  ErrorReport err{};
  err.error = Error::kNotReady;
  err.offending_type = 0x11;

  // Valid frames of every message.
  save("valid_hello", frame(Hello{}));
  save("valid_capabilities", frame(caps));
  save("valid_config", frame(cfg, 2, flags::kAckRequested));
  save("valid_ack", frame(ack));
  save("valid_nack", frame(nack));
  save("valid_ping", frame(ping));
  save("valid_pong", frame(pong));
  save("valid_reset", frame(reset, 3, flags::kAckRequested));
  save("valid_shutdown", frame(shutdown, 4));
  save("valid_odometry", frame(odo));
  save("valid_obs_batch_0", frame(batch(0)));
  save("valid_obs_batch_3", frame(batch(3)));
  save("valid_obs_batch_20", frame(batch(20)));
  save("valid_obs_batch_24", frame(batch(24)));
  save("valid_assoc_result", frame(assoc));
  save("valid_pose", frame(pose));
  save("valid_stats_request", frame(StatsRequest{}));
  save("valid_stats", frame(stats));
  save("valid_error", frame(err));

  // A session: delimiter, HELLO, CONFIG, RESET, ODOMETRY, OBS_BATCH, with garbage in between.
  Bytes session = {0};
  for (const Bytes& f : {frame(Hello{}, 1), frame(cfg, 2), Bytes{0x13, 0x37, 0x00}, frame(reset, 3), frame(odo, 4),
                         frame(batch(5), 5), Bytes{0, 0, 0}}) {
    session.insert(session.end(), f.begin(), f.end());
  }
  save("stream_session", session);

  // Truncated frames (no trailing part, then a delimiter) and single-bit flips.
  const Bytes b3 = frame(batch(3));
  for (const std::size_t k : {1u, 7u, 12u, 30u, 60u}) {
    Bytes t(b3.begin(), b3.begin() + static_cast<std::ptrdiff_t>(k));
    t.push_back(0);
    save("truncated_obs_batch_3_at_" + std::to_string(k), t);
  }
  const Bytes po = frame(ping);
  for (const std::size_t k : {3u, 9u, 14u}) {
    Bytes t(po.begin(), po.begin() + static_cast<std::ptrdiff_t>(k));
    t.push_back(0);
    save("truncated_ping_at_" + std::to_string(k), t);
  }
  const Bytes od = frame(odo);
  for (const std::size_t i : {0u, 2u, 9u, 20u, 30u}) {
    Bytes f = od;
    f[i] = static_cast<std::uint8_t>(f[i] ^ 0x10);
    save("bitflip_odometry_" + std::to_string(i), f);
  }
  for (const std::size_t i : {1u, 40u}) {
    Bytes f = b3;
    f[i] = static_cast<std::uint8_t>(f[i] ^ 0x01);
    save("bitflip_obs_batch_3_" + std::to_string(i), f);
  }

  // Framing errors.
  save("empty_frames", Bytes(8, 0));
  Bytes over(kMaxEncodedBody + 5, 0x41);
  over.push_back(0);
  const Bytes after = frame(ping);
  over.insert(over.end(), after.begin(), after.end());
  save("overrun_then_ping", over);
  Bytes garbage;
  for (int i = 0; i < 64; ++i) garbage.push_back(static_cast<std::uint8_t>((i * 97 + 13) & 0xFF));
  garbage.insert(garbage.end(), after.begin(), after.end());
  save("garbage_then_ping", garbage);

  // Valid CRC, rejected later.
  const Bytes pp = payload(ping);
  const auto t_ping = static_cast<std::uint8_t>(MsgType::kPing);
  save("bad_version", raw(2, 0, t_ping, 4, pp));
  save("bad_len_field", raw(1, 0, t_ping, 5, pp));
  save("incompatible_flag", raw(1, 0x20, t_ping, 4, pp));
  save("compatible_flag", raw(1, 0x08, t_ping, 4, pp));
  save("unknown_type", raw(1, 0, 0x55, 4, pp));
  Bytes op = payload(odo);
  put_u32_le(op.data() + 8, 0x7FC00000u);  // dt_s = NaN
  save("odometry_nan", raw(1, 0, static_cast<std::uint8_t>(MsgType::kOdometry), 20, op));
  Bytes bp = payload(batch(24));
  bp[4] = 25;
  bp.resize(5 + 25 * 20, 0x3F);
  save("obs_batch_over_capacity",
       raw(1, 0, static_cast<std::uint8_t>(MsgType::kObsBatch), static_cast<std::uint16_t>(bp.size()), bp));
  Bytes bl = payload(batch(3));
  bl.resize(bl.size() - 20);
  save("obs_batch_len_vs_count",
       raw(1, 0, static_cast<std::uint8_t>(MsgType::kObsBatch), static_cast<std::uint16_t>(bl.size()), bl));
  Bytes rp = payload(reset);
  put_u32_le(rp.data() + 12, float_bits(-1.0f));  // p00 < 0
  save("reset_not_pd", raw(1, 0, static_cast<std::uint8_t>(MsgType::kReset), 36, rp));

  // Raw payloads (the fuzz target also decodes the whole input as a payload).
  save("payload_config", payload(cfg));
  save("payload_obs_batch_3", payload(batch(3)));
  save("payload_assoc_result", payload(assoc));

  std::printf("wrote %d files to %s\n", g_files, g_dir.c_str());
  return 0;
}
