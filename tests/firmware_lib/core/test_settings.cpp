// The option table (core/options.h) and the settings built from it (core/settings.hpp): one default
// per option on every surface (library, wire, C), every option carried through the C boundary and
// through CONFIG, every range enforced by configure(), and the one strategy parser.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include "geojcbb/c_settings.hpp"
#include "geojcbb/node/node.hpp"
#include "support/options.hpp"

using namespace geojcbb;
using geojcbb::test::with_other;

namespace {

/// Option k of a and b agree at float32 precision (what CONFIG carries).
template <typename A, typename B>
bool same_at_float(const A& a, const B& b, int k) {
  bool same = true;
  for_each_option_pair(a, b, [&](const options::Info& info, const auto& x, const auto& y) {
    if (&info - options::kInfo != k) return;
    same = static_cast<float>(options::as_double(x)) == static_cast<float>(options::as_double(y));
  });
  return same;
}

template <class M>
std::vector<std::uint8_t> payload_of(const M& m) {
  std::vector<std::uint8_t> p(M::kMaxPayloadSize);
  std::size_t n = 0;
  REQUIRE(m.encode(p.data(), p.size(), n) == proto::Error::kOk);
  p.resize(n);
  return p;
}

}  // namespace

TEST_CASE("options: every default is in its range, and the defaults configure a SLAM step") {
  const StepSettings<double> d;
  for_each_option(d, [](const options::Info& info, const auto& v) {
    const std::string option = info.name;
    CAPTURE(option);
    CHECK(info.range.contains(options::as_double(v)));
    CHECK(options::index_of(info.name) == &info - options::kInfo);
  });
  CHECK(in_range(d));
  auto step = std::make_unique<node::SlamStep<double, DefaultBounds>>();
  CHECK(step->configure(d) == Status::kOk);
}

TEST_CASE("options: one default per option: the library's, the wire's and the C API's agree") {
  const StepSettings<float> lib;
  // The wire: CONFIG's defaults are the library's (node/wire.hpp also checks it at compile time) ...
  CHECK(payload_of(proto::Config{}) == payload_of(node::config_from(lib)));
  // ... and a default CONFIG configures the device as the library's defaults do (levels at float32).
  const StepSettings<float> wire = node::settings_from<float, DefaultBounds>(proto::Config{});
  for (int k = 0; k < options::kCount; ++k) {
    const std::string option = options::kInfo[k].name;
    CAPTURE(option);
    CHECK(same_at_float(wire, lib, k));
  }
  // C: geojcbb_settings_default is the table's default, through the product's own boundary.
  geojcbb_settings c;
  std::memset(&c, 0xA5, sizeof c);
  c = c_boundary::to_c(lib);
  CHECK(same_settings(c_boundary::from_c(c), lib));
}

TEST_CASE("options: every option crosses the C boundary and CONFIG, none is dropped") {
  int carried = 0;
  for (int k = 0; k < options::kCount; ++k) {
    const std::string option = options::kInfo[k].name;
    CAPTURE(option);
    const StepSettings<float> s = with_other<float>(k);
    REQUIRE(in_range(s));
    REQUIRE(!same_settings(s, StepSettings<float>{}));
    CHECK(same_settings(c_boundary::from_c(c_boundary::to_c(s)), s));
    if (node::carried_by_config(k)) {
      ++carried;
      const StepSettings<double> back = node::settings_from<double, DefaultBounds>(node::config_from(s));
      CHECK(same_at_float(back, s, k));
      CHECK(!same_at_float(back, StepSettings<float>{}, k));
    }
  }
  // Every option reaches a device today; a future host-only option would be refused by the link
  // (host_tools/link/stream.cpp) instead.
  CHECK(carried == options::kCount);
}

/// CONFIG field K accepts a wire value exactly when the table's range holds it (what configure()
/// checks on the device): probed at every value of a byte and around each bound of a real.
template <std::size_t K>
void check_wire_range() {
  constexpr auto f = std::get<K>(proto::Config::fields());
  constexpr int i = node::config_wire::option_of<K>();
  if constexpr (i >= 0) {
    using W = std::remove_reference_t<decltype(proto::Config{}.*(f.member))>;
    const options::Info& info = options::kInfo[i];
    CAPTURE(info.name);
    if constexpr (std::is_same<W, float>::value) {
      const float inf = std::numeric_limits<float>::infinity();
      std::vector<float> probes = {0.0f,
                                   -0.0f,
                                   1.0f,
                                   -1.0f,
                                   0.5f,
                                   100.0f,
                                   -100.0f,
                                   1e6f,
                                   1e30f,
                                   -1e30f,
                                   inf,
                                   -inf,
                                   std::numeric_limits<float>::quiet_NaN()};
      for (const double bound : {info.range.lo, info.range.hi}) {
        const float b = static_cast<float>(bound);
        probes.insert(probes.end(), {b, std::nextafter(b, inf), std::nextafter(b, -inf)});
      }
      for (const float v : probes) {
        CAPTURE(v);
        CHECK((proto::check_float(f.range, v) == proto::Error::kOk) == info.range.contains(static_cast<double>(v)));
      }
    } else if constexpr (std::is_same<W, bool>::value) {
      CHECK(f.range.kind == proto::Range::Kind::kOneOf);  // a bool's domain: 0 and 1
      CHECK((f.range.lo == 0 && f.range.hi == 1));
    } else {
      static_assert(sizeof(W) <= 4, "an integer field");
      std::vector<std::int64_t> probes;
      for (std::int64_t v = 0; v <= 255; ++v) probes.push_back(v);
      if (sizeof(W) > 1)
        probes.insert(probes.end(), {256, 65535, static_cast<std::int64_t>(std::numeric_limits<W>::max())});
      for (const std::int64_t v : probes) {
        CAPTURE(v);
        CHECK(proto::int_in_range(f.range, v) == info.range.contains(static_cast<double>(v)));
      }
    }
  }
}
template <std::size_t... K>
void check_wire_ranges(std::index_sequence<K...>) {
  (check_wire_range<K>(), ...);
}

TEST_CASE("options: CONFIG's range of each field is the table's") {
  check_wire_ranges(std::make_index_sequence<node::config_wire::kFieldCount>{});
}

TEST_CASE_TEMPLATE("options: configure refuses every option outside its range and changes nothing", T, float, double) {
  auto step = std::make_unique<node::SlamStep<T, DefaultBounds>>();
  for (int k = 0; k < options::kCount; ++k) {
    const options::Range r = options::kInfo[k].range;
    if (r.kind == options::RangeKind::kANY) continue;
    const std::string option = options::kInfo[k].name;
    CAPTURE(option);
    StepSettings<T> s;
    for_each_option(s, [&](const options::Info& info, auto& v) {
      using V = std::remove_reference_t<decltype(v)>;
      if (&info - options::kInfo != k) return;
      const double bad = r.lo - 1;  // below every range's low end
      if constexpr (std::is_enum<V>::value) {
        v = static_cast<V>(200);
      } else if constexpr (std::is_unsigned<V>::value) {
        v = static_cast<V>(0);
      } else {
        v = static_cast<V>(bad);
      }
    });
    const bool out = !in_range(s);
    if (!out) continue;  // an unsigned option whose range starts at 0
    CHECK(step->configure(s) == Status::kInvalidInput);
    CHECK(!step->configured());
  }
  StepSettings<T> s;
  s.max_range_m = s.min_range_m;  // the one rule across options
  CHECK(step->configure(s) == Status::kInvalidInput);
  s = StepSettings<T>{};
  s.confidence = std::nan("");
  CHECK(step->configure(s) == Status::kInvalidInput);
}

TEST_CASE("options: the one strategy parser") {
  Strategy s = Strategy::kIcnn;
  bool v = true;
  for (int k = 0; k < kStrategyCount; ++k) {
    const char* name = to_string(static_cast<Strategy>(k));
    REQUIRE(parse_strategy(name, s, v));
    CHECK(s == static_cast<Strategy>(k));
    CHECK(!v);
  }
  REQUIRE(parse_strategy("jcbb+v", s, v));
  CHECK(s == Strategy::kJcbb);
  CHECK(v);
  REQUIRE(parse_strategy("GeoJcbb", s, v));
  CHECK(s == Strategy::kGeojcbb);
  CHECK(!v);
  s = Strategy::kIcnn;
  v = false;
  for (const char* bad : {"", "JCB", "JCBBX", "JCBB+", "JCBB+VV", "+V", "KJCBB V", "NOPE"}) {
    CAPTURE(bad);
    CHECK(!parse_strategy(bad, s, v));
  }
  CHECK(s == Strategy::kIcnn);  // nothing written on failure
  CHECK(!v);
}
