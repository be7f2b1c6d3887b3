// The preset grammar (core/presets.hpp), the one every tool and Python read: each suffix of the table
// alone and in combination, case and order free, the canonical name, and every bad name refused with
// nothing written.
#include <doctest/doctest.h>

#include <string>

#include "geojcbb/core/presets.hpp"

using namespace geojcbb;

TEST_CASE("presets: every strategy, alone and with every suffix of the table") {
  for (int s = 0; s < kStrategyCount; ++s) {
    const std::string base = to_string(static_cast<Strategy>(s));
    Preset p;
    REQUIRE(parse_preset(base.c_str(), p));
    CHECK(p.strategy == static_cast<Strategy>(s));
    CHECK(p.suffixes == 0);
    for (int k = 0; k < kPresetSuffixCount; ++k) {
      const char letter = kPresetSuffixes[k].letter;
      CAPTURE(letter);
      for (const char c : {letter, static_cast<char>(letter - 'A' + 'a')}) {
        Preset q;
        REQUIRE(parse_preset((base + "+" + c).c_str(), q));
        CHECK(q.strategy == static_cast<Strategy>(s));
        CHECK(q.suffixes == (1u << k));
        CHECK(q.has(letter));
      }
    }
  }
}

TEST_CASE("presets: combinations in any order, and the canonical name in table order") {
  Preset p;
  REQUIRE(parse_preset("pcjcbb+lr", p));
  char name[kMaxPresetName + 1];
  preset_name(p, name);
  CHECK(std::string(name) == "PCJCBB+RL");
  REQUIRE(parse_preset("JCBB+CHTLRV", p));
  preset_name(p, name);
  CHECK(std::string(name) == "JCBB+VRLTHC");
  REQUIRE(parse_preset("PCJCBB+V", p));  // PCJCBB verifies anyway: the V is not named
  preset_name(p, name);
  CHECK(std::string(name) == "PCJCBB");
  for (int bits = 0; bits < (1 << kPresetSuffixCount); ++bits) {  // every combination round-trips
    Preset a;
    a.strategy = Strategy::kGeojcbb;
    a.suffixes = static_cast<std::uint8_t>(bits);
    preset_name(a, name);
    Preset b;
    REQUIRE(parse_preset(name, b));
    CHECK(b.suffixes == a.suffixes);
  }
}

TEST_CASE("presets: a bad name is refused and nothing is written") {
  for (const char* bad : {"", "+", "JCBB+", "JCBB+X", "JCBB+RR", "JCBB+rR", "JCBB+R+L", "+RL", "JCBBX", "JCB",
                          "JCBB+VRLTHCV", "GEOJCBBGEOJCBB+R", "JCBB +R"}) {
    CAPTURE(bad);
    Preset p;
    p.strategy = Strategy::kIcnn;
    p.suffixes = 0x55;
    CHECK_FALSE(parse_preset(bad, p));
    CHECK(p.strategy == Strategy::kIcnn);
    CHECK(p.suffixes == 0x55);
  }
}

TEST_CASE("presets: each suffix switches its piece into the settings, and a piece already on stays on") {
  StepSettings<double> s;
  Preset p;
  REQUIRE(parse_preset("PCJCBB+VRLTHC", p));
  apply_preset(p, s);
  CHECK(s.strategy == Strategy::kPcjcbb);
  CHECK(s.verify);
  CHECK(s.relocalise);
  CHECK(s.loop_check);
  CHECK(s.tentative_isolated);
  CHECK(s.hypothesis_rivals == kPresetRivals);
  CHECK(s.cluster_first);
  StepSettings<double> t;
  t.loop_check = true;
  t.hypothesis_rivals = 1;
  REQUIRE(parse_preset("JCBB+H", p));
  apply_preset(p, t);
  CHECK(t.loop_check);
  CHECK(t.hypothesis_rivals == 1);  // set by the caller: kept
  CHECK_FALSE(t.relocalise);
  CHECK_FALSE(t.verify);
  // Every letter of the table changes the settings (no letter without its piece).
  for (int k = 0; k < kPresetSuffixCount; ++k) {
    Preset one;
    one.strategy = Strategy::kJcbb;
    one.suffixes = static_cast<std::uint8_t>(1u << k);
    StepSettings<double> a, b;
    apply_preset(one, a);
    one.suffixes = 0;
    apply_preset(one, b);
    CAPTURE(kPresetSuffixes[k].letter);
    CHECK((a.verify != b.verify || a.relocalise != b.relocalise || a.loop_check != b.loop_check ||
           a.tentative_isolated != b.tentative_isolated || a.hypothesis_rivals != b.hypothesis_rivals ||
           a.cluster_first != b.cluster_first));
  }
}
