// consistency: a fixed-capacity undirected graph with bitset adjacency (the consistency graph of
// pairings; Bailey's CCDA 2002, Mangelson et al.'s PCM 2018), and the bitset it is built from.
// Storage: MaxNodes rows of ceil(MaxNodes / 64) uint64_t words (64 nodes: 64 x 64 bits = 512 B).
// Bounds: every loop runs over at most MaxNodes nodes or kWords words. No self loops.
#pragma once

#include <array>
#include <cstdint>

namespace geojcbb {

/// Nodes of a consistency graph by default: one 64-bit word per adjacency row.
constexpr int kDefaultGraphNodes = 64;

/// A set of node indices 0 .. MaxNodes-1.
template <int MaxNodes>
struct NodeSet {
  static_assert(MaxNodes >= 1 && MaxNodes <= 256, "node indices fit uint8");
  static constexpr int kWords = (MaxNodes + 63) / 64;
  using Word = std::uint64_t;
  std::array<Word, kWords> w;

  void clear() {
    for (int k = 0; k < kWords; ++k) w[k] = 0;  // <= kWords
  }
  void set(int v) { w[v >> 6] |= Word(1) << (v & 63); }
  void reset(int v) { w[v >> 6] &= ~(Word(1) << (v & 63)); }
  bool test(int v) const { return (w[v >> 6] >> (v & 63)) & 1u; }
  bool any() const {
    for (int k = 0; k < kWords; ++k) {  // <= kWords
      if (w[k] != 0) return true;
    }
    return false;
  }
  int count() const {
    int n = 0;
    for (int k = 0; k < kWords; ++k) n += __builtin_popcountll(w[k]);  // <= kWords
    return n;
  }
  /// Lowest member, or -1 when empty.
  int lowest() const {
    for (int k = 0; k < kWords; ++k) {  // <= kWords
      if (w[k] != 0) return 64 * k + __builtin_ctzll(w[k]);
    }
    return -1;
  }
  /// this = a & b
  void assign_and(const NodeSet& a, const NodeSet& b) {
    for (int k = 0; k < kWords; ++k) w[k] = a.w[k] & b.w[k];  // <= kWords
  }
  /// this &= ~a
  void subtract(const NodeSet& a) {
    for (int k = 0; k < kWords; ++k) w[k] &= ~a.w[k];  // <= kWords
  }
  /// The first n indices.
  void fill(int n) {
    for (int k = 0; k < kWords; ++k) {  // <= kWords
      const int lo = 64 * k;
      w[k] = n >= lo + 64 ? ~Word(0) : (n > lo ? (Word(1) << (n - lo)) - 1 : Word(0));
    }
  }
  bool operator==(const NodeSet& o) const {
    for (int k = 0; k < kWords; ++k) {  // <= kWords
      if (w[k] != o.w[k]) return false;
    }
    return true;
  }
  bool operator!=(const NodeSet& o) const { return !(*this == o); }
};

/// Undirected simple graph on `count` <= MaxNodes nodes; row v of adj is the neighbourhood N(v).
template <int MaxNodes = kDefaultGraphNodes>
struct BitsetGraph {
  static constexpr int kMaxNodes = MaxNodes;
  using Set = NodeSet<MaxNodes>;
  int count = 0;
  std::array<Set, MaxNodes> adj;

  /// Empties the graph and sets its node count (0 .. MaxNodes; clamped).
  void reset(int n) {
    count = n < 0 ? 0 : (n > MaxNodes ? MaxNodes : n);
    for (int v = 0; v < MaxNodes; ++v) adj[v].clear();  // <= MaxNodes
  }
  /// Adds edge {u, v}; a self loop is ignored. Precondition: 0 <= u, v < count.
  void add_edge(int u, int v) {
    if (u == v) return;
    adj[u].set(v);
    adj[v].set(u);
  }
  bool has_edge(int u, int v) const { return adj[u].test(v); }
  int degree(int v) const { return adj[v].count(); }
  int edges() const {
    int e = 0;
    for (int v = 0; v < count; ++v) e += adj[v].count();  // <= MaxNodes
    return e / 2;
  }
  /// True when every member of s is a node and every pair of members is adjacent.
  bool is_clique(const Set& s) const {
    for (int v = 0; v < MaxNodes; ++v) {  // <= MaxNodes
      if (!s.test(v)) continue;
      if (v >= count) return false;
      Set others = s;
      others.reset(v);
      others.subtract(adj[v]);
      if (others.any()) return false;
    }
    return true;
  }
};

}  // namespace geojcbb
