// Diagnostics computed from the particle state during a run.
#pragma once
#include <cstdint>
#include <vector>

#include "engine/particles.hpp"
#include "engine/thermo.hpp"

namespace smpm {

// Leading edge of the compression wave in one body, along y. The body's particles are binned
// in rows of height `dy` (the cell size); a row is "reached" when its mean y-velocity differs
// from the body's initial vy0 by more than half of |vy0| (half the particle-velocity jump of an
// impact that brings it to rest). Scanning from the end away from the impact plane (`from_top`:
// the body lies above the plane), the front is where the mean crosses that level, interpolated
// linearly between row centres. Returns NaN when no row is reached. Needs vy0 != 0.
double front_position(const Particles& P, std::uint8_t body, double vy0, double y0, double dy, int rows,
                      bool from_top);

// Temperature of particle p [K] (T0 where the particle carries no energy); the stored share
// (1 - heat_fraction) of its plastic work does not count as heat.
double particle_temperature(const Particles& P, std::size_t p, const Thermo& th, const Material& m);

}  // namespace smpm
