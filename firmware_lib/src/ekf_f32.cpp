// The EKF-SLAM filter in float at the default bounds, instantiated whole so the cross build's checks
// (no heap symbols, frame sizes, call chains) cover every member.
#include "geojcbb/ekf/slam.hpp"

template class geojcbb::ekf::Slam<float, geojcbb::DefaultBounds>;
