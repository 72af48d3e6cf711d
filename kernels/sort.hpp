// Binning of particles by tile and cell: a stable parallel counting sort of an index.
// The result is identical for any thread count (stability: within a cell, particles keep
// their array order), which the bitwise-determinism guarantee of the whole step rests on.
#pragma once
#include <cstddef>
#include <cstdint>

#include "views.hpp"

namespace smpm::kern {

// Key of the cell holding (x, y): tile-major, then row-major inside the tile.
// Returns false (and leaves key untouched) when the point is outside [x0, x0+nx h) x [y0, y0+ny h).
inline bool cell_key(const GridGeom& g, double x, double y, std::uint32_t& key) {
  const double xg = (x - g.x0) / g.h, yg = (y - g.y0) / g.h;
  // also rejects NaN
  if (!(xg >= 0.0 && xg < g.nx && yg >= 0.0 && yg < g.ny)) return false;
  const int cx = static_cast<int>(xg), cy = static_cast<int>(yg);
  const int tx = cx / g.tile, ty = cy / g.tile;
  const int lx = cx - tx * g.tile, ly = cy - ty * g.tile;
  key = static_cast<std::uint32_t>((ty * g.tiles_x() + tx) * g.cells_per_tile() + ly * g.tile + lx);
  return true;
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
