// protocol_bench: throughput of the serial link's codec on the host, and its framing overhead.
//   decoder: a long stream of 20-observation OBS_BATCH frames fed one byte at a time to Decoder::push,
//            then each frame decoded as an ObsBatch (MB/s of wire bytes)
//   encoder: encode_message of the same batches (validation, payload, CRC-32C, COBS) (MB/s of wire bytes)
//   baseline, same run: CRC-32C alone over the same bytes, so the figures read as ratios.
// Timing is reported, never asserted; the CTest smoke run (bench.protocol_smoke) only checks it runs.
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <vector>

#include <CLI/CLI.hpp>

#include "geojcbb/protocol/protocol.hpp"
#include "geojcbb_host/guarded_main.hpp"

namespace {

using namespace geojcbb::proto;
using Clock = std::chrono::steady_clock;

ObsBatch make_batch(std::uint32_t id, int count) {
  ObsBatch b{};
  b.batch_id = id;
  b.count = static_cast<std::uint8_t>(count);
  for (int i = 0; i < count; ++i) {
    ObservationWire& o = b.obs[static_cast<std::size_t>(i)];
    const float k = static_cast<float>(i) + 0.001f * static_cast<float>(id % 1000);
    o.range_m = 0.5f + 0.41f * k;
    o.bearing_rad = -3.0f + 0.29f * static_cast<float>(i);
    o.r00 = 0.0025f;
    o.r01 = 0.00001f * k;
    o.r11 = 0.0003f;
  }
  return b;
}

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

}  // namespace

namespace {

int run(int argc, char** argv) {
  CLI::App app{"geojcbb protocol benchmark (timing is measured, never asserted)"};
  int frames = 2000;
  int repeat = 50;
  int obs = 20;
  app.add_option("--frames", frames, "OBS_BATCH frames in the stream")->check(CLI::PositiveNumber);
  app.add_option("--repeat", repeat, "passes over the stream")->check(CLI::PositiveNumber);
  app.add_option("--obs", obs, "observations per batch")->check(CLI::Range(0, static_cast<int>(ObsBatch::kCapacity)));
  CLI11_PARSE(app, argc, argv);

  // The stream, and the batches it carries.
  std::vector<ObsBatch> batches;
  std::vector<std::uint8_t> stream;
  batches.reserve(static_cast<std::size_t>(frames));
  EncodedFrame ef;
  std::size_t payload_bytes = 0;
  for (int i = 0; i < frames; ++i) {
    batches.push_back(make_batch(static_cast<std::uint32_t>(i), obs));
    if (encode_message(batches.back(), static_cast<std::uint16_t>(i), 0, ef) != Error::kOk) {
      std::fprintf(stderr, "encode failed\n");
      return 1;
    }
    stream.insert(stream.end(), ef.bytes.begin(), ef.bytes.begin() + static_cast<std::ptrdiff_t>(ef.size));
    payload_bytes += batches.back().payload_size();
  }
  const double wire_mb = static_cast<double>(stream.size()) * repeat / 1e6;

  // Baseline: CRC-32C alone over the same bytes.
  std::uint32_t sink = 0;
  auto t0 = Clock::now();
  for (int r = 0; r < repeat; ++r) sink += crc32c(stream.data(), stream.size());
  const double t_crc = seconds_since(t0);

  // Decoder: byte by byte, then each frame decoded as an ObsBatch.
  Decoder dec;
  std::uint64_t decoded = 0;
  t0 = Clock::now();
  for (int r = 0; r < repeat; ++r) {
    for (const std::uint8_t byte : stream) {
      FrameView f;
      if (dec.push(byte, f) != Error::kOk) continue;
      ObsBatch b;
      if (decode_message(f, b) == Error::kOk) {
        ++decoded;
        sink += b.batch_id;
      }
    }
  }
  const double t_dec = seconds_since(t0);

  // Decoder, framing only (no message decode).
  Decoder dec2;
  std::uint64_t framed = 0;
  t0 = Clock::now();
  for (int r = 0; r < repeat; ++r) {
    for (const std::uint8_t byte : stream) {
      FrameView f;
      if (dec2.push(byte, f) == Error::kOk) {
        ++framed;
        sink += f.seq;
      }
    }
  }
  const double t_frame = seconds_since(t0);

  // Encoder: validation, payload, CRC, COBS, delimiter.
  std::uint64_t wire_out = 0;
  t0 = Clock::now();
  for (int r = 0; r < repeat; ++r) {
    for (std::size_t i = 0; i < batches.size(); ++i) {
      if (encode_message(batches[i], static_cast<std::uint16_t>(i), 0, ef) == Error::kOk) {
        wire_out += ef.size;
        sink += ef.bytes[ef.size / 2];
      }
    }
  }
  const double t_enc = seconds_since(t0);

  const std::uint64_t expected = static_cast<std::uint64_t>(frames) * static_cast<std::uint64_t>(repeat);
  const ObsBatch one = make_batch(1, obs);
  if (encode_message(one, 1, 0, ef) != Error::kOk) return 1;
  const std::size_t pl = one.payload_size();

  std::printf("protocol_bench: %d frames x %d passes, %d observations per OBS_BATCH (checksum %08x)\n", frames, repeat,
              obs, static_cast<unsigned>(sink));
  std::printf(
      "frame overhead: payload %zu B, wire %zu B (header 8 + CRC 4 + COBS %zu + delimiter 1) = +%zu B, "
      "%.1f %% efficiency; worst case %zu B\n",
      pl, ef.size, ef.size - pl - 13, ef.size - pl, 100.0 * static_cast<double>(pl) / static_cast<double>(ef.size),
      max_wire_size(pl));
  std::printf("stream: %zu wire bytes for %zu payload bytes\n", stream.size(), payload_bytes);
  std::printf("%-34s %10.1f MB/s  (1.00x)\n", "baseline CRC-32C", wire_mb / t_crc);
  std::printf("%-34s %10.1f MB/s  (%.2fx of CRC)  %llu/%llu frames\n", "decoder push() + ObsBatch decode",
              wire_mb / t_dec, t_crc / t_dec, static_cast<unsigned long long>(decoded),
              static_cast<unsigned long long>(expected));
  std::printf("%-34s %10.1f MB/s  (%.2fx of CRC)  %llu/%llu frames\n", "decoder push() only", wire_mb / t_frame,
              t_crc / t_frame, static_cast<unsigned long long>(framed), static_cast<unsigned long long>(expected));
  std::printf("%-34s %10.1f MB/s  (%.2fx of CRC)  %.0f frames/s\n", "encoder encode_message()",
              static_cast<double>(wire_out) / 1e6 / t_enc, t_crc / t_enc, static_cast<double>(expected) / t_enc);
  const DecoderCounters& c = dec.counters();
  if (decoded != expected || framed != expected || c.bad_crc + c.bad_length + c.overrun != 0) {
    std::fprintf(stderr, "protocol_bench: frames lost\n");
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return geojcbb::host::guarded_main(run, argc, argv); }
