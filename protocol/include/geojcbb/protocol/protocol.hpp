// protocol: everything of the serial link in one include (framing, CRC-32C, COBS, schema, messages,
// codec). Standard library only; no heap, no exceptions, no RTTI. Specification: docs/protocol.md.
#pragma once

#include "geojcbb/protocol/cobs.hpp"
#include "geojcbb/protocol/codec.hpp"
#include "geojcbb/protocol/crc32c.hpp"
#include "geojcbb/protocol/error.hpp"
#include "geojcbb/protocol/frame.hpp"
#include "geojcbb/protocol/messages.hpp"
#include "geojcbb/protocol/schema.hpp"
#include "geojcbb/protocol/wire.hpp"
