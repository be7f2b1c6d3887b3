// core: a preset's name, "BASE" or "BASE+LETTERS": BASE one of the seven strategies (parse_strategy,
// case-insensitive), each LETTER (case-insensitive, any order, each at most once) switching one piece
// of the step into it. One table, kPresetSuffixes, read by every command-line tool, by Python and by
// the tests; apply_preset() writes the pieces into a step's settings. Bounds: a name of at most
// kMaxPresetName characters.
#pragma once

#include <cstdint>

#include "geojcbb/core/settings.hpp"

namespace geojcbb {

struct PresetSuffix {
  char letter;       ///< upper case
  const char* what;  ///< the piece it switches in, for help texts
};

/// The suffix letters, in the order a preset's canonical name lists them.
inline constexpr PresetSuffix kPresetSuffixes[] = {
    {'V', "verification"},                  // verify (PCJCBB verifies anyway)
    {'R', "relocaliser"},                   // relocalise
    {'L', "loop-closure check"},            // loop_check
    {'T', "tentative landmarks isolated"},  // tentative_isolated
    {'H', "hypothesis window"},             // hypothesis_rivals = kPresetRivals unless set
    {'C', "clusters paired first"},         // cluster_first
};
inline constexpr int kPresetSuffixCount = static_cast<int>(sizeof(kPresetSuffixes) / sizeof(kPresetSuffixes[0]));
/// The rivals the suffix H keeps beside the best (unless hypothesis_rivals is set).
inline constexpr int kPresetRivals = 2;
/// The longest name parse_preset reads: a strategy's (8) + '+' + every letter once.
inline constexpr int kMaxPresetName = 8 + 1 + kPresetSuffixCount;

/// A parsed preset: the strategy and the suffixes switched in (bit k: kPresetSuffixes[k]).
struct Preset {
  Strategy strategy = Strategy::kGeojcbb;
  std::uint8_t suffixes = 0;

  /// The suffix with this (upper-case) letter is switched in.
  bool has(char letter) const {
    for (int k = 0; k < kPresetSuffixCount; ++k) {  // <= kPresetSuffixCount
      if (kPresetSuffixes[k].letter == letter) return (suffixes >> k) & 1u;
    }
    return false;
  }
};

/// Reads "BASE" or "BASE+LETTERS". @return true and `out` set; false (nothing written) for an unknown
/// strategy, an unknown or repeated letter, a bare '+', or a name longer than kMaxPresetName.
inline bool parse_preset(const char* text, Preset& out) {
  auto upper = [](char c) { return c >= 'a' && c <= 'z' ? static_cast<char>(c - 'a' + 'A') : c; };
  char base[kMaxPresetName + 1] = {};
  int n = 0;
  while (text[n] != '\0' && text[n] != '+') {  // <= kMaxPresetName
    if (n >= kMaxPresetName) return false;
    base[n] = text[n];
    ++n;
  }
  Preset p;
  bool verify = false;
  if (!parse_strategy(base, p.strategy, verify)) return false;
  if (text[n] == '+') {
    ++n;
    if (text[n] == '\0') return false;                // a bare '+'
    for (int len = 0; text[n] != '\0'; ++n, ++len) {  // <= kPresetSuffixCount letters
      if (len >= kPresetSuffixCount) return false;
      int k = 0;
      while (k < kPresetSuffixCount && kPresetSuffixes[k].letter != upper(text[n])) ++k;  // <= kPresetSuffixCount
      if (k == kPresetSuffixCount || ((p.suffixes >> k) & 1u)) return false;
      p.suffixes = static_cast<std::uint8_t>(p.suffixes | (1u << k));
    }
  }
  out = p;
  return true;
}

/// The preset's canonical name into buf (at least kMaxPresetName + 1 bytes): the strategy, then '+'
/// and its letters in table order; V left out for PCJCBB (it verifies anyway).
inline void preset_name(const Preset& p, char* buf) {
  int n = 0;
  for (const char* s = to_string(p.strategy); *s != '\0'; ++s) buf[n++] = *s;  // <= 8
  const int plus = n;
  buf[n++] = '+';
  for (int k = 0; k < kPresetSuffixCount; ++k) {  // <= kPresetSuffixCount
    const char c = kPresetSuffixes[k].letter;
    if (((p.suffixes >> k) & 1u) && !(c == 'V' && p.strategy == Strategy::kPcjcbb)) buf[n++] = c;
  }
  if (n == plus + 1) n = plus;  // no letter: no '+'
  buf[n] = '\0';
}

/// The preset into a step's settings: the strategy, and each suffix's piece switched in (a piece
/// already on stays on; H sets hypothesis_rivals to kPresetRivals when it is 0).
template <typename T>
void apply_preset(const Preset& p, StepSettings<T>& s) {
  s.strategy = p.strategy;
  s.verify = s.verify || p.has('V');
  s.relocalise = s.relocalise || p.has('R');
  s.loop_check = s.loop_check || p.has('L');
  s.tentative_isolated = s.tentative_isolated || p.has('T');
  if (p.has('H') && s.hypothesis_rivals == 0) s.hypothesis_rivals = kPresetRivals;
  s.cluster_first = s.cluster_first || p.has('C');
}

}  // namespace geojcbb
