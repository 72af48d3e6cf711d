// Grid phases: clear, periodic fold, momentum update with forces and walls, ghost refresh.
#pragma once
#include <cstddef>

#include "views.hpp"

namespace smpm::kern {

enum class Wall : int { None = 0, Slip = 1, NoSlip = 2 };

// Walls sit on the domain edges x = x0, x0 + nx h, y = y0, y0 + ny h. A wall constrains every
// node on or beyond it: Slip zeroes the normal velocity, NoSlip both components.
struct Walls {
  Wall left = Wall::None, right = Wall::None, bottom = Wall::None, top = Wall::None;
};

struct GridUpdateParams {
  double dt = 0.0;
  double gravity_x = 0.0, gravity_y = 0.0;  // [m/s^2]
  // Nodes with 0 < mass <= mass_eps (a particle's stencil tail, e.g. a linear-hat particle just
  // past a node) move with their momentum only: a force over such a mass would give an
  // arbitrarily large acceleration that the velocity gradient picks up through grad w.
  double mass_eps = 0.0;
  Walls walls;
  bool flip = false;      // also store dv = v_new - v_old
};

// Reaction of each wall on the material, summed per storage row so that the total is
// formed in a fixed order (deterministic for any thread count). row_force has kRowSlots * sy()
// entries per call: [left x, right x, bottom y, top y] per row; the caller sums them.
inline constexpr int kRowSlots = 4;
void grid_update(const GridGeom& g, const GridView& G, const GridUpdateParams& q, double* row_force);

// MUSL remap: velocity = momentum / mass, walls applied, no forces.
void grid_velocity_from_momentum(const GridGeom& g, const GridView& G, const GridUpdateParams& q);

// Zero the arrays a P2G writes (mass and forces only when `all`).
void clear_grid(const GridGeom& g, const GridView& G, bool all);

// Periodic x: add ghost-column sums onto their real columns (after P2G), and copy real
// columns into ghost columns (after the grid update) for the arrays named.
void fold_periodic(const GridGeom& g, double* const* arrays, int count);
void fill_periodic_ghosts(const GridGeom& g, double* const* arrays, int count);

}  // namespace smpm::kern
