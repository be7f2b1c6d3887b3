// host_tools/link: a transport that drops and corrupts bytes, as a real robot's UART does
// (docs/protocol.md, "Fault injection").
//   LinkFaults       the fault process: a byte error rate and the mix of drops, bit flips and bursts,
//                    a seed; parsed from a spec such as "ber=1e-4,drop=0.5,burst=0.1,seed=7,reset=120".
//   FaultChannel     one direction's faults, deterministic from the seed.
//   FaultLine        both directions' channels and their counters, shared by the transports one
//                    session opens one after another (a reopened port continues the same sequence).
//   FaultTransport   wraps (owns) another Transport and applies a FaultLine to what is written
//                    (host -> device) and what is read (device -> host).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <random>
#include <string>

#include "geojcbb_host/serial.hpp"

namespace geojcbb::host {

/// Per byte, with probability `byte_error_rate`, a fault event: with probability `burst_fraction` a
/// burst (this byte and the next L - 1, L uniform in [burst_min, burst_max], each dropped with
/// probability `drop_fraction`, else one random bit of it flipped), otherwise one byte dropped (with
/// probability `drop_fraction`) or one random bit of it flipped. Bytes inside a burst start no event.
struct LinkFaults {
  double byte_error_rate = 0;         ///< ber: fault events per byte, [0, 1]
  double drop_fraction = 0.5;         ///< drop: of single-byte events (and of a burst's bytes), the drops, [0, 1]
  double burst_fraction = 0.1;        ///< burst: of the events, the bursts, [0, 1]
  int burst_min = 8, burst_max = 64;  ///< burst_min, burst_max: a burst's length in bytes, 1 <= min <= max
  std::uint64_t seed = 1;             ///< seed: the same seed, the same faults for the same bytes
  double reset_every_s = 0;           ///< reset: a device reset every N seconds of log (0: none); carried only, the
                                      ///< streaming acts on it
  /// Faults are injected (byte_error_rate > 0).
  bool injects() const { return byte_error_rate > 0; }
  /// The spec, every key: "ber=0.0001,drop=0.5,burst=0.1,burst_min=8,burst_max=64,seed=7,reset=120"
  /// (parse_link_faults gives back the same values).
  std::string describe() const;
};

/// "key=value,..." with the keys of LinkFaults (ber, drop, burst, burst_min, burst_max, seed, reset),
/// each at most once, the others at their defaults; "" and "none": no faults. Throws
/// std::invalid_argument naming the key or value that is wrong (unknown key, not a number, out of
/// range, burst_min > burst_max, repeated key).
LinkFaults parse_link_faults(const std::string& spec);

/// What one direction's faults did.
struct FaultDirectionCounts {
  std::uint64_t passed = 0;       ///< bytes delivered unchanged
  std::uint64_t dropped = 0;      ///< bytes lost (in a burst or not)
  std::uint64_t corrupted = 0;    ///< bytes delivered with one bit flipped (in a burst or not)
  std::uint64_t bursts = 0;       ///< bursts started
  std::uint64_t burst_bytes = 0;  ///< bytes inside bursts (dropped or corrupted; included above)
  /// Bytes offered: passed + dropped + corrupted.
  std::uint64_t bytes() const { return passed + dropped + corrupted; }
  /// Fault events: single drops and flips, and bursts.
  std::uint64_t events() const { return dropped + corrupted - burst_bytes + bursts; }
  /// Bytes at which an event could start (those outside bursts, and each burst's first).
  std::uint64_t trials() const { return bytes() - burst_bytes + bursts; }
};

struct FaultCounts {
  FaultDirectionCounts to_device;    ///< bytes the host writes
  FaultDirectionCounts from_device;  ///< bytes the host reads
  /// "to device: N bytes, D dropped, C corrupted, B bursts; from device: ..."
  std::string describe() const;
};

/// One direction's fault process: a std::mt19937_64 and the burst in progress.
class FaultChannel {
 public:
  /// `stream` tells the directions apart (the same seed gives each its own sequence).
  FaultChannel(const LinkFaults& f, std::uint64_t stream);
  /// Applies the faults to [p, p + n) in place: dropped bytes are removed (the others keep their
  /// order); returns the bytes kept. Counts into `c`.
  std::size_t apply(std::uint8_t* p, std::size_t n, FaultDirectionCounts& c);

 private:
  double uniform();
  LinkFaults f_;
  std::mt19937_64 rng_;
  int burst_left_ = 0;  ///< bytes of the current burst still to come
};

/// The faults of one link across its reopenings, and their counters.
struct FaultLine {
  explicit FaultLine(const LinkFaults& f) : faults(f), to_device(f, 0), from_device(f, 1) {}
  LinkFaults faults;
  FaultChannel to_device, from_device;
  FaultCounts counts;
};

/// A Transport whose bytes go through a FaultLine. Not for concurrent use (as the transports it wraps).
class FaultTransport : public Transport {
 public:
  /// Faults of its own, from f.seed.
  FaultTransport(std::unique_ptr<Transport> inner, const LinkFaults& f);
  /// Continues `line` (shared with the transports opened before and after this one).
  FaultTransport(std::unique_ptr<Transport> inner, std::shared_ptr<FaultLine> line);
  /// Reads from the inner transport and applies the faults; when every byte read was dropped it reads
  /// again until timeout_ms has passed (0 still means the timeout).
  std::size_t read(std::uint8_t* p, std::size_t n, int timeout_ms) override;
  /// Applies the faults, then writes what is left (nothing when every byte was dropped).
  void write(const std::uint8_t* p, std::size_t n) override;
  const FaultCounts& counts() const { return line_->counts; }
  /// The line, which outlives this transport (its counters stay readable).
  const std::shared_ptr<FaultLine>& line() const { return line_; }

 private:
  std::unique_ptr<Transport> inner_;
  std::shared_ptr<FaultLine> line_;
};

/// SessionOptions::open with faults: every port `open` makes is wrapped in a FaultTransport on
/// `line` (so a reconnection continues the fault sequence rather than repeating it).
std::function<std::unique_ptr<Transport>()> open_with_faults(std::function<std::unique_ptr<Transport>()> open,
                                                             std::shared_ptr<FaultLine> line);

}  // namespace geojcbb::host
