#include "geojcbb_host/fault_transport.hpp"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <stdexcept>
#include <utility>
#include <vector>

namespace geojcbb::host {

namespace {

/// The shortest decimal that reads back as v.
std::string shortest(double v) {
  char b[32];
  if (v == std::floor(v) && std::abs(v) < 1e15) {
    std::snprintf(b, sizeof b, "%.0f", v);
    return b;
  }
  for (int prec = 1; prec <= 17; ++prec) {
    std::snprintf(b, sizeof b, "%.*g", prec, v);
    if (std::strtod(b, nullptr) == v) break;
  }
  return b;
}

[[noreturn]] void bad(const std::string& key, const std::string& value, const std::string& why) {
  throw std::invalid_argument("link faults: " + key + "=" + value + ": " + why);
}

double parse_real(const std::string& key, const std::string& value, double lo, double hi) {
  const char* s = value.c_str();
  char* end = nullptr;
  const double v = std::strtod(s, &end);
  if (value.empty() || end != s + value.size() || !std::isfinite(v)) bad(key, value, "not a number");
  if (v < lo || v > hi) bad(key, value, "outside [" + shortest(lo) + ", " + shortest(hi) + "]");
  return v;
}

std::uint64_t parse_unsigned(const std::string& key, const std::string& value) {
  const char* s = value.c_str();
  char* end = nullptr;
  errno = 0;
  const unsigned long long v = std::strtoull(s, &end, 10);
  if (value.empty() || value[0] == '-' || value[0] == '+' || end != s + value.size() || errno == ERANGE) {
    bad(key, value, "not an unsigned integer");
  }
  return v;
}

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t");
  if (a == std::string::npos) return "";
  const auto b = s.find_last_not_of(" \t");
  return s.substr(a, b - a + 1);
}

std::string direction(const char* name, const FaultDirectionCounts& c) {
  return std::string(name) + ": " + std::to_string(c.bytes()) + " bytes, " + std::to_string(c.dropped) + " dropped, " +
         std::to_string(c.corrupted) + " corrupted, " + std::to_string(c.bursts) + " bursts (" +
         std::to_string(c.events()) + " fault events)";
}

}  // namespace

std::string LinkFaults::describe() const {
  return "ber=" + shortest(byte_error_rate) + ",drop=" + shortest(drop_fraction) +
         ",burst=" + shortest(burst_fraction) + ",burst_min=" + std::to_string(burst_min) +
         ",burst_max=" + std::to_string(burst_max) + ",seed=" + std::to_string(seed) +
         ",reset=" + shortest(reset_every_s);
}

LinkFaults parse_link_faults(const std::string& spec) {
  LinkFaults f;
  const std::string all = trim(spec);
  if (all.empty() || all == "none") return f;
  std::set<std::string> seen;
  std::size_t at = 0;
  while (at <= all.size()) {
    const std::size_t comma = std::min(all.find(',', at), all.size());
    const std::string item = trim(all.substr(at, comma - at));
    at = comma + 1;
    const std::size_t eq = item.find('=');
    if (eq == std::string::npos) {
      std::string what = "link faults: '";
      what += item;
      what += "' is not key=value (in '";
      what += spec;
      what += "')";
      throw std::invalid_argument(what);
    }
    const std::string key = trim(item.substr(0, eq));
    const std::string value = trim(item.substr(eq + 1));
    if (!seen.insert(key).second) bad(key, value, "given twice");
    if (key == "ber") {
      f.byte_error_rate = parse_real(key, value, 0, 1);
    } else if (key == "drop") {
      f.drop_fraction = parse_real(key, value, 0, 1);
    } else if (key == "burst") {
      f.burst_fraction = parse_real(key, value, 0, 1);
    } else if (key == "burst_min" || key == "burst_max") {
      const std::uint64_t v = parse_unsigned(key, value);
      if (v < 1 || v > 1000000) bad(key, value, "outside [1, 1000000]");
      (key == "burst_min" ? f.burst_min : f.burst_max) = static_cast<int>(v);
    } else if (key == "seed") {
      f.seed = parse_unsigned(key, value);
    } else if (key == "reset") {
      f.reset_every_s = parse_real(key, value, 0, 1e9);
    } else {
      throw std::invalid_argument("link faults: unknown key '" + key +
                                  "' (ber, drop, burst, burst_min, burst_max, seed, reset)");
    }
  }
  if (f.burst_min > f.burst_max) {
    throw std::invalid_argument("link faults: burst_min=" + std::to_string(f.burst_min) +
                                " is over burst_max=" + std::to_string(f.burst_max));
  }
  return f;
}

std::string FaultCounts::describe() const {
  return direction("to device", to_device) + "; " + direction("from device", from_device);
}

FaultChannel::FaultChannel(const LinkFaults& f, std::uint64_t stream) : f_(f) {
  std::seed_seq s{static_cast<std::uint32_t>(f.seed), static_cast<std::uint32_t>(f.seed >> 32),
                  static_cast<std::uint32_t>(stream)};
  rng_.seed(s);
}

double FaultChannel::uniform() { return std::uniform_real_distribution<double>(0.0, 1.0)(rng_); }

std::size_t FaultChannel::apply(std::uint8_t* p, std::size_t n, FaultDirectionCounts& c) {
  std::size_t out = 0;
  for (std::size_t i = 0; i < n; ++i) {
    std::uint8_t b = p[i];
    bool drop = false, flip = false;
    if (burst_left_ > 0) {
      --burst_left_;
      ++c.burst_bytes;
      drop = uniform() < f_.drop_fraction;
      flip = !drop;
    } else if (f_.byte_error_rate > 0 && uniform() < f_.byte_error_rate) {
      if (uniform() < f_.burst_fraction) {
        ++c.bursts;
        burst_left_ = std::uniform_int_distribution<int>(f_.burst_min, f_.burst_max)(rng_) - 1;
        ++c.burst_bytes;
      }
      drop = uniform() < f_.drop_fraction;
      flip = !drop;
    }
    if (flip) {
      b = static_cast<std::uint8_t>(b ^ (1U << std::uniform_int_distribution<int>(0, 7)(rng_)));
      ++c.corrupted;
    } else if (drop) {
      ++c.dropped;
      continue;
    } else {
      ++c.passed;
    }
    p[out++] = b;
  }
  return out;
}

FaultTransport::FaultTransport(std::unique_ptr<Transport> inner, const LinkFaults& f)
    : FaultTransport(std::move(inner), std::make_shared<FaultLine>(f)) {}

FaultTransport::FaultTransport(std::unique_ptr<Transport> inner, std::shared_ptr<FaultLine> line)
    : inner_(std::move(inner)), line_(std::move(line)) {
  if (!inner_ || !line_) throw std::invalid_argument("FaultTransport: no transport or no fault line");
}

std::size_t FaultTransport::read(std::uint8_t* p, std::size_t n, int timeout_ms) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  for (;;) {
    const std::size_t got = inner_->read(p, n, timeout_ms);
    if (got == 0) return 0;
    const std::size_t kept = line_->from_device.apply(p, got, line_->counts.from_device);
    if (kept > 0) return kept;
    // Everything read was dropped: wait for more in what is left of the timeout.
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return 0;
    timeout_ms = static_cast<int>(left.count());
  }
}

void FaultTransport::write(const std::uint8_t* p, std::size_t n) {
  std::vector<std::uint8_t> bytes(p, p + n);
  const std::size_t kept = line_->to_device.apply(bytes.data(), n, line_->counts.to_device);
  if (kept > 0) inner_->write(bytes.data(), kept);
}

std::function<std::unique_ptr<Transport>()> open_with_faults(std::function<std::unique_ptr<Transport>()> open,
                                                             std::shared_ptr<FaultLine> line) {
  if (!open || !line) throw std::invalid_argument("open_with_faults: no way to open the port or no fault line");
  return [open = std::move(open), line = std::move(line)]() -> std::unique_ptr<Transport> {
    return std::make_unique<FaultTransport>(open(), line);
  };
}

}  // namespace geojcbb::host
