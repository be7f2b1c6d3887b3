// host_tools/datasets: the converters of geojcbb_eval convert-mrclam and convert-victoria-park: a
// MRCLAM robot (with the replay's model, or raw) or ACFR's Victoria Park written as a log of
// docs/replay.md's format, to be replayed with `replay --log`.
#pragma once

#include <string>

#include "geojcbb_host/mrclam_replay.hpp"
#include "geojcbb_host/victoria_park.hpp"

namespace geojcbb::host {

/// A MRCLAM robot as a log (docs/replay.md): with its model (what MrclamSource feeds the filter,
/// as `geojcbb_eval mrclam --datasets D --robots R` builds it) or raw.
struct MrclamConvertOptions {
  std::string data_dir, out;
  int dataset = 6, robot = 1;
  double seconds = 0;  ///< > 0: only the first seconds
  bool raw = false;
  MrclamOptions model;  ///< the model switches, as for `mrclam`
};
/// Writes the log to c.out and prints what it holds. Throws std::runtime_error when the data cannot
/// be read or the file written. Returns the process exit code (0).
int convert_mrclam(const MrclamConvertOptions& c);

/// Victoria Park as a log (docs/victoria_park.md): the rear axle's increments, the laser's mount,
/// the detections kept, GPS.
struct VictoriaConvertOptions {
  std::string data_dir, out;
  victoria_park::ConvertOptions model;
};
/// As convert_mrclam, for Victoria Park.
int convert_victoria_park(const VictoriaConvertOptions& c);

}  // namespace geojcbb::host
