// Tests: a device's reply to one scan (ASSOC_RESULT and POSE) against the in-process float step's
// result for the same scan, bit for bit: each pairing's outcome, feature and d2, the pose and its
// covariance's upper triangle, and the landmark count.
#pragma once

#include <cstdint>
#include <cstring>

#include "geojcbb/node/slam_step.hpp"
#include "geojcbb_host/link.hpp"

namespace geojcbb::test {

inline std::uint32_t bits(float f) {
  std::uint32_t u;
  std::memcpy(&u, &f, sizeof u);
  return u;
}

struct ReplyCheck {
  long mismatches = 0;  ///< differing values
  long paired = 0;      ///< pairings in the device's reply
};

template <class B>
ReplyCheck check_reply(const host::LinkClient::ScanReply& r, const node::StepResult<float, B>& res,
                       const ekf::Slam<float, B>& sl) {
  ReplyCheck c;
  for (int i = 0; i < res.count; ++i) {
    const proto::PairingWire& q = r.result.pairs[static_cast<std::size_t>(i)];
    const bool same = static_cast<int>(q.outcome) == static_cast<int>(res.outcome[i]) &&
                      (q.feature_id >= 0 ? q.feature_id == res.feature[i] : res.feature[i] == -1) &&
                      bits(q.d2) == bits(res.d2[i]);
    c.mismatches += !same;
    c.paired += q.outcome == proto::PairingOutcome::kPaired;
  }
  const float mine[] = {sl.x(0),      sl.x(1),      sl.x(2),      sl.cov(0, 0), sl.cov(0, 1),
                        sl.cov(0, 2), sl.cov(1, 1), sl.cov(1, 2), sl.cov(2, 2)};
  const float theirs[] = {r.pose.x_m,          r.pose.y_m,          r.pose.theta_rad,
                          r.pose.cov_upper[0], r.pose.cov_upper[1], r.pose.cov_upper[2],
                          r.pose.cov_upper[3], r.pose.cov_upper[4], r.pose.cov_upper[5]};
  for (int k = 0; k < 9; ++k) c.mismatches += bits(mine[k]) != bits(theirs[k]);
  c.mismatches += r.pose.landmark_count != sl.landmarks();
  return c;
}

}  // namespace geojcbb::test
