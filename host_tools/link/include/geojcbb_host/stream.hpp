// host_tools/link: a simulated scenario as link messages, and a run of it through a device, scored
// like the evaluation (TP/TN/FP/FN as in docs/evaluation.md, pose error against the truth).
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "geojcbb_host/link.hpp"
#include "geojcbb_host/slam_run.hpp"

namespace geojcbb::host {

proto::Config link_config(const Scenario& sc, Strategy s, const RunOptions& o);
proto::Reset link_reset(const Scenario& sc);
proto::Odometry link_odometry(const Scenario& sc, const SimStep& step);
/// The scan's observations, nearest first, at most kLinkMaxObs (`kept` receives their truths).
LinkObsBatch link_batch(const Scenario& sc, const std::vector<SimObservation>& scan, std::uint32_t batch_id,
                        std::vector<int>& kept);

/// What a device answered for one scan, with the scan's truths.
using ScanHook = std::function<void(const LinkObsBatch&, const LinkClient::ScanReply&)>;

/// Streams one seed of a scenario through a device: CONFIG, RESET, then per control interval
/// ODOMETRY and per scan OBS_BATCH, scoring each ASSOC_RESULT. Throws LinkError on a link failure.
RunResult stream_scenario(LinkClient& link, const Scenario& sc, std::uint64_t seed, Strategy s, const RunOptions& o,
                          const ScanHook& hook = nullptr);

}  // namespace geojcbb::host
