// Binning of particles by tile and cell: a stable parallel counting sort of an index.
// The result is identical for any thread count (stability: within a cell, particles keep
// their array order), which the bitwise-determinism guarantee of the whole step rests on.
#pragma once
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "views.hpp"

namespace smpm::kern {

// What a cell key needs of the grid, as doubles: integer arithmetic in doubles is exact here
// (every value is an integer below 2^32) and the vector units do it without conversions; and
// no integer division (GridGeom::tiles_x) left in the loop, which GCC does not hoist.
struct KeyGeom {
  double x0, y0, inv_h, nx, ny, tile, inv_tile, tiles_x, cells_per_tile;
  explicit KeyGeom(const GridGeom& g)
      : x0(g.x0), y0(g.y0), inv_h(1.0 / g.h), nx(g.nx), ny(g.ny), tile(g.tile), inv_tile(1.0 / g.tile),
        tiles_x(g.tiles_x()), cells_per_tile(g.cells_per_tile()) {}
};

// Key of the cell holding (x, y): tile-major, then row-major inside the tile. Grid units are
// (x - x0) * (1 / h), the same expression as the transfers' (kernels/transfer.hpp): a key and a
// stencil computed from one position agree on its cell even at a cell edge, which the colored
// scatter's tile halo relies on. Branch-free, so compute_keys vectorizes. Returns false (key
// then holds the key of cell (0, 0)) when the point is outside [x0, x0+nx h) x [y0, y0+ny h) or NaN.
SMPM_INLINE bool cell_key(const KeyGeom& g, double x, double y, std::uint32_t& key) {
  const double xg = (x - g.x0) * g.inv_h, yg = (y - g.y0) * g.inv_h;
  // also rejects NaN
  const bool inside = (xg >= 0.0) & (xg < g.nx) & (yg >= 0.0) & (yg < g.ny);
  const double cx = inside ? std::trunc(xg) : 0.0, cy = inside ? std::trunc(yg) : 0.0;
  double tx = std::trunc(cx * g.inv_tile), ty = std::trunc(cy * g.inv_tile);
  tx = (tx + 1.0) * g.tile <= cx ? tx + 1.0 : tx;  // cx * (1 / tile) may round below an integer
  ty = (ty + 1.0) * g.tile <= cy ? ty + 1.0 : ty;
  const double lx = cx - tx * g.tile, ly = cy - ty * g.tile;
  key = static_cast<std::uint32_t>((ty * g.tiles_x + tx) * g.cells_per_tile + ly * g.tile + lx);
  return inside;
}

// Computes key[i] for every particle. Returns the lowest index of a particle outside the
// grid (or NaN), or -1 when all are inside.
std::ptrdiff_t compute_keys(const GridGeom& g, const double* x, const double* y, std::size_t n,
                            std::uint32_t* key);

// Stable counting sort of the keys. Outputs: cell_start[k] (size nkeys + 1), the first sorted
// position of key k; order[s], the particle at sorted position s. hist is scratch of
// at least omp_get_max_threads() * nkeys entries.
void counting_sort(const std::uint32_t* key, std::size_t n, std::size_t nkeys, std::uint32_t* hist,
                   std::uint32_t* cell_start, std::uint32_t* order);

// out[s] = in[order[s]]: physical permutation of one particle array into sorted order.
template <class T>
void gather_permute(const T* in, const std::uint32_t* order, std::size_t n, T* out) {
#pragma omp parallel for schedule(static)
  for (std::size_t s = 0; s < n; ++s) out[s] = in[order[s]];
}

}  // namespace smpm::kern
