// host_tools/sim: families of generated worlds (docs/simulator.md, "Generated worlds"). A world is a
// Scenario drawn from a family's stated parameter ranges, reproducible from (family, seed), and
// written as a scenario JSON so that any world can be run again with --scenario. The families are
// the places where decisions that outlive a scan fail: look-alike rows, periodic corridors, big
// drifting loops, blind stretches, heavy clutter, kidnaps, small and large maps.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "geojcbb_host/sim.hpp"

namespace geojcbb::host {

struct WorldFamily {
  const char* name;
  const char* ranges;  ///< what is drawn, and from where (the help text and the docs)
};

/// Every family, in the order `--worlds` takes them in turn.
const std::vector<WorldFamily>& world_families();

/// The world `seed` of `family`: every parameter drawn uniformly from the family's ranges with a
/// generator seeded from both. Throws std::invalid_argument for an unknown family.
Scenario draw_world(const std::string& family, std::uint64_t seed);

/// Writes `s` as a scenario JSON that load_scenario reads back (landmarks as an explicit list).
/// Throws std::runtime_error when the file cannot be written.
void save_scenario(const Scenario& s, const std::string& path);

}  // namespace geojcbb::host
