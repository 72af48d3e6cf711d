// Binning of particles by tile and cell: a stable parallel counting sort of an index.
// The result is identical for any thread count (stability: within a cell, particles keep
// their array order), which the bitwise-determinism guarantee of the whole step rests on.
#pragma once
#include "dimension.hpp"
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "tensor.hpp"
#include "views.hpp"

namespace SMPM_NS::kern {

// What a cell key needs of the grid, as doubles: integer arithmetic in doubles is exact here
// (every value is an integer below 2^32) and the vector units do it without conversions; and
// no integer division (GridGeom::tiles) left in the loop, which GCC does not hoist.
struct KeyGeom {
  // per axis: origin [m], cells, tiles
  double origin[kDim], n[kDim], tiles[kDim];
  double inv_h, tile, inv_tile, cells_per_tile;
  explicit KeyGeom(const GridGeom& g)
      : inv_h(1.0 / g.h), tile(g.tile), inv_tile(1.0 / g.tile), cells_per_tile(g.cells_per_tile()) {
    for (int d = 0; d < kDim; ++d) {
      origin[d] = g.origin(d);
      n[d] = g.cells(d);
      tiles[d] = g.tiles(d);
    }
  }
};

// Key of the cell holding point pt: tile-major (tiles numbered with x fastest), then the cell
// inside the tile (x fastest). Grid units are (x - origin) * (1 / h), the same expression as the
// transfers' (kernels/transfer.hpp): a key and a stencil computed from one position agree on its
// cell even at a cell edge, which the colored scatter's tile halo relies on. Every value is an
// integer below 2^32, so the arithmetic in doubles is exact. Branch-free, so sort_by_cell's key loop
// vectorizes; the point comes by value and the result is returned (a pointer to a local array
// or an output reference inside the `omp simd` loop kept it scalar and 6x slower). inside is
// false (key then that of cell 0) when the point is outside the grid's cells
// [origin, origin + n h) on some axis, or NaN.
struct CellKey {
  std::uint32_t key;
  bool inside;
};
SMPM_INLINE CellKey cell_key(const KeyGeom& g, const Vec<kDim> pt) {
  double u[kDim], c[kDim], t[kDim];
  bool inside = true;
#pragma GCC unroll 3
  for (int d = 0; d < kDim; ++d) {
    u[d] = (pt[d] - g.origin[d]) * g.inv_h;
    inside = inside & (u[d] >= 0.0) & (u[d] < g.n[d]);  // also rejects NaN
  }
#pragma GCC unroll 3
  for (int d = 0; d < kDim; ++d) c[d] = inside ? std::trunc(u[d]) : 0.0;
#pragma GCC unroll 3
  for (int d = 0; d < kDim; ++d) t[d] = std::trunc(c[d] * g.inv_tile);
#pragma GCC unroll 3
  for (int d = 0; d < kDim; ++d) t[d] = (t[d] + 1.0) * g.tile <= c[d] ? t[d] + 1.0 : t[d];  // c / tile may round below an integer
  double tile = t[kDim - 1], cell = c[kDim - 1] - t[kDim - 1] * g.tile;
#pragma GCC unroll 3
  for (int d = kDim - 2; d >= 0; --d) {
    tile = tile * g.tiles[d] + t[d];
    cell = cell * g.tile + (c[d] - t[d] * g.tile);
  }
  return {static_cast<std::uint32_t>(tile * g.cells_per_tile + cell), inside};
}

// Bins the particles, pos[d] their coordinate arrays: key[i], the key of particle i's cell, for
// every particle; then a stable counting sort of the keys into cell_start[k] (size nkeys + 1),
// the first sorted position of key k, and order[s], the particle at sorted position s. hist is
// scratch of at least omp_get_max_threads() * nkeys entries. Returns -1, or the lowest index of
// a particle outside the grid (or NaN): then cell_start and order are not formed.
std::ptrdiff_t sort_by_cell(const GridGeom& g, const double* const* pos, std::size_t n, std::uint32_t* key,
                            std::uint32_t* hist, std::uint32_t* cell_start, std::uint32_t* order);

// out[s] = in[order[s]]: physical permutation of one particle array into sorted order.
template <class T>
void gather_permute(const T* in, const std::uint32_t* order, std::size_t n, T* out) {
#pragma omp parallel for schedule(static)
  for (std::size_t s = 0; s < n; ++s) out[s] = in[order[s]];
}

}  // namespace SMPM_NS::kern
