// The device loop in float at the default bounds, instantiated whole so the cross build's checks
// (no heap symbols, frame sizes, call chains) cover it.
#include "geojcbb/node/node.hpp"

template class geojcbb::node::Node<float, geojcbb::DefaultBounds>;
