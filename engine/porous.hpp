// Porous samples (docs/model.md, "Porous sample"): random overlapping circular voids cut from a
// dense lattice of points. Void centres are uniform in the body's rectangle; every point within
// a void's radius is removed; voids may overlap. The porosity is the fraction of points removed.
#pragma once
#include "kernels/dimension.hpp"
#include <cstddef>
#include <cstdint>
#include <vector>

#include "engine/geometry.hpp"
#include "engine/particles.hpp"

namespace SMPM_NS {

struct Void {
  Vector c{};    // centre [m]
  double r = 0;  // radius [m]
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

// Cuts voids from the points of P: one body on the lattice of spacing `step` whose points sit at
// origin + (i + 1/2) step (i a lattice index per axis), inside the half-open box [lo, hi). Along
// an axis with period[d] > 0 distances wrap with that period (periodic sides, geometry.hpp's
// periods), so voids cross the side boundaries. P is compacted in place, keeping the order of the
// rest.
PorousResult cut_voids(Particles& P, double step, const Vector& origin, const Box& box, const VoidSpec& spec,
                       const Vector& period);

// Mirror image of P about the plane where axis `axis` is `plane` [m] (for the symmetric two-body
// collision): positions and velocities along that axis reflected.
Particles mirror(const Particles& P, int axis, double plane);

// Separated void faces: puts each point of P in velocity field 0 or 1 by the side of its
// nearest void (nearest surface, |x - c| - r) it lies on along the unit direction s (the impact
// direction): 1 where (x - c) . s > 0. The two faces of a void that a shock closes along s then
// lie in different fields, which approach each other freely until they meet (kern::grid_contact,
// weld). Points with no void within `reach` [m] of their surface take field 0. Along an axis
// with period[d] > 0 distances wrap. nfields = 4 splits each side again across s: field + 2 where
// (x - c) . t > 0, t = (s_y, -s_x) (s turned by -90 degrees in the plane of axes 0 and 1:
// (x - c) . t is the cross product (x - c) x s at D = 2), so that the faces of a void that close
// across s (a void a few cells wide collapses from all sides) lie in different fields too. Sets
// P.field (0 .. nfields - 1).
void assign_void_sides(Particles& P, const std::vector<Void>& voids, const Vector& s, double reach,
                       const Vector& period, int nfields = 2);

}  // namespace SMPM_NS
