// Porous samples (docs/model.md, "Porous sample"): random overlapping circular voids cut from a
// dense lattice of points. Void centres are uniform in the body's rectangle; every point within
// a void's radius is removed; voids may overlap. The porosity is the fraction of points removed.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "engine/particles.hpp"

namespace smpm {

struct Void {
  double x = 0, y = 0, r = 0;  // centre and radius [m]
};

struct VoidSpec {
  double radius = 0.0;         // mean void radius [m]
  double radius_spread = 0.0;  // radii uniform in [radius - spread, radius + spread] [m]
  double porosity = -1.0;      // target porosity: voids are added until it is reached, or
  long count = -1;             // a fixed number of voids
  std::uint64_t seed = 1;      // same seed, same sample (generation is serial)
  long max_voids = 100000000;  // a bound on the random voids drawn (a porosity target may stop short)
  std::vector<Void> centers;   // explicit voids instead (radius and seed unused)
};

struct PorousResult {
  long voids = 0;
  double porosity = 0.0;  // achieved: removed points / points of the dense body
  std::vector<Void> cut;  // the voids, in the order drawn
};

// Cuts voids from the points of P: one body on the lattice of spacing d whose points sit at
// (ox + (a + 1/2) d, oy + (b + 1/2) d), inside [x0, x1) x [y0, y1). With `period` > 0 distances
// in x wrap with that period (periodic sides), so voids cross the side boundaries. P is
// compacted in place, keeping the order of the rest.
PorousResult cut_voids(Particles& P, double d, double ox, double oy, double x0, double x1, double y0, double y1,
                       const VoidSpec& spec, double period);

// Mirror image of P about the line y = y_plane (for the symmetric two-body collision).
Particles mirror_y(const Particles& P, double y_plane);

// Separated void faces: puts each point of P in velocity field 0 or 1 by the side of its
// nearest void (nearest surface, |x - c| - r) it lies on along the unit direction (sx, sy)
// (the impact direction): 1 where (x - c) . s > 0. The two faces of a void that a shock
// closes along s then lie in different fields, which approach each other freely until they
// meet (kern::grid_contact, weld). Points with no void within `reach` [m] of their surface
// take field 0. period > 0: distances in x wrap. nfields = 4 splits each side again across s:
// field + 2 where (x - c) x s = (x - c)_x s_y - (x - c)_y s_x > 0, so that the faces of a void
// that close across s (a void a few cells wide collapses from all sides) lie in different fields
// too. Sets P.field (0 .. nfields - 1).
void assign_void_sides(Particles& P, const std::vector<Void>& voids, double sx, double sy, double reach,
                       double period, int nfields = 2);

}  // namespace smpm
