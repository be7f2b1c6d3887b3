// The EKF-SLAM filter and the SLAM step (filter + association) in float at the default bounds,
// instantiated whole so the cross build's checks (no heap symbols, frame sizes, call chains) cover
// every member.
#include "geojcbb/ekf/slam.hpp"
#include "geojcbb/node/slam_step.hpp"

template class geojcbb::ekf::Slam<float, geojcbb::DefaultBounds>;
template class geojcbb::node::SlamStep<float, geojcbb::DefaultBounds>;
