// node: the local map's hand-over, node::Node's SUBMAP_SEED (the global map's landmarks seeded into
// the local map), SUBMAP_ACK (the next map, or the closed one sent again) and the SUBMAP and
// SUBMAP_COV frames read in place from the filter; declared and documented in node/node.hpp, defined
// here. Bounds: n / 16 + 1 + D (D + 1) / 192 + 1 frames for n landmarks, D = 3 + 2 n; kMaxSeeds seeds
// a frame (docs/submaps.md). Definitions `inline` as in the class, but the gnu::noinline ones.
#pragma once

#include <cstddef>
#include <cstdint>

#include "geojcbb/node/node.hpp"

namespace geojcbb::node {

template <typename T, class B>
proto::Error Node<T, B>::serve_seed(const proto::FrameView& f) {
  return serve<proto::SubmapSeed>(f);
}

template <typename T, class B>
void Node<T, B>::on_message(const proto::SubmapSeed& m) {
  if (!running()) return;
  if (!fresh()) {  // retransmitted: seeded once; its answer again while it is the last one
    if (have_result_ && m.batch_id == result_.batch_id) send(result_);
    return;
  }
  if (busy()) return;
  if (m.map_id != map_id_) {
    invalid();
    return;
  }
  MapSeed<T> seeds[kMaxSeeds];
  for (int k = 0; k < m.count; ++k) {  // <= kMaxSeeds
    const proto::SeedWire& w = m.items[static_cast<std::size_t>(k)];
    seeds[k].l << T(w.x_m), T(w.y_m);
    seeds[k].P << T(w.p00), T(w.p01), T(w.p01), T(w.p11);
    seeds[k].exist_nats = T(w.exist_nats);
  }
  if (step_.seed(seeds, m.count, seed_answers_) != Status::kOk) {
    invalid();
    return;
  }
  result_.batch_id = m.batch_id;
  result_.count = m.count;
  for (int k = 0; k < m.count; ++k) {  // <= kMaxSeeds
    proto::PairingWire& q = result_.pairs[static_cast<std::size_t>(k)];
    q.outcome = static_cast<proto::PairingOutcome>(seed_answers_[k].outcome);
    q.feature_id = seed_answers_[k].id;
    q.d2 = static_cast<float>(seed_answers_[k].d2);
  }
  send(result_);
  applied();
  have_result_ = true;
}

template <typename T, class B>
inline void Node<T, B>::on_message(const proto::SubmapAck& m) {
  if (!running()) return;
  if (!handing_over_) {
    if (m.send && m.map_id == map_id_) {  // the current map, closed now at this scan boundary
      handing_over_ = true;
      ack();
      send_submap();
    } else if (have_handed_ && m.map_id + 1 == map_id_ && !m.send) {  // the last map's again (its ACK lost)
      ack();
    } else {
      nack(proto::Error::kOutOfRange);
    }
    return;
  }
  if (m.map_id != map_id_) {
    nack(proto::Error::kOutOfRange);
    return;
  }
  if (m.send) {  // frames lost, or a reconnection: the same map again, from the same memory
    ack();
    send_submap();
    return;
  }
  if (step_.restart() != Status::kOk) {  // the map stays, pending: the host may ask for it again
    nack(proto::Error::kInternal);
    return;
  }
  handing_over_ = false;
  have_handed_ = true;
  ++map_id_;
  ack();
}

template <typename T, class B>
inline void Node<T, B>::send_submap() {
  const std::uint16_t frames =
      static_cast<std::uint16_t>(proto::submap_frames(static_cast<std::uint32_t>(step_.slam().landmarks())));
  send_submap_cov(send_submap_landmarks(frames), frames);
}

template <typename T, class B>
std::uint16_t Node<T, B>::send_submap_landmarks(std::uint16_t frames) {
  const ekf::Slam<T, B>& s = step_.slam();
  const int n = s.landmarks();
  std::uint16_t chunk = 0;
  proto::Submap m;
  m.map_id = map_id_;
  m.chunks = frames;
  m.landmarks = static_cast<std::uint16_t>(n);
  m.x_m = static_cast<float>(s.x(0));
  m.y_m = static_cast<float>(s.x(1));
  m.theta_rad = static_cast<float>(s.x(2));
  const int per = static_cast<int>(proto::kSubmapLandmarksPerFrame);
  for (int first = 0; first == 0 || first < n; first += per) {  // <= kMaxLandmarks / 16 + 1
    m.chunk = chunk++;
    m.first = static_cast<std::uint16_t>(first);
    m.count = static_cast<std::uint8_t>(n - first < per ? n - first : per);
    for (int k = 0; k < m.count; ++k) {  // <= 16
      proto::SubmapLandmarkWire& w = m.items[static_cast<std::size_t>(k)];
      const int j = first + k;
      const Vec2<T> l = s.landmark(j);
      w.id = s.id(j);
      w.x_m = static_cast<float>(l.x());
      w.y_m = static_cast<float>(l.y());
      w.confirmed = s.confirmed(j);
      w.exist_nats = static_cast<float>(s.existence(j));
      w.carried = step_.carried(j);
    }
    send_out_of_line(m);
  }
  return chunk;
}

template <typename T, class B>
void Node<T, B>::send_submap_cov(std::uint16_t chunk, std::uint16_t frames) {
  const ekf::Slam<T, B>& s = step_.slam();
  proto::SubmapCov m;
  m.map_id = map_id_;
  m.chunks = frames;
  const int d = s.dim();
  int r = 0, c = 0;  // the next entry, column by column
  std::uint32_t offset = 0;
  while (c < d) {  // <= kPackedSize / 96 + 1 frames
    m.chunk = chunk++;
    m.offset = offset;
    m.count = 0;
    while (c < d && m.count < proto::kSubmapCovPerFrame) {  // <= 96
      m.items[m.count++].v = static_cast<float>(s.cov(r, c));
      ++offset;
      if (++r > c) {
        r = 0;
        ++c;
      }
    }
    send_out_of_line(m);
  }
}

template <typename T, class B>
template <class M>
void Node<T, B>::send_out_of_line(const M& m) {
  send(m);
}

}  // namespace geojcbb::node
