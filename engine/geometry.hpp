// The engine's geometry over kern::kDim axes: positions and velocities, boxes, the impact axis,
// and loops over boxes of lattice indices.
#pragma once
#include "kernels/dimension.hpp"
#include <cmath>

#include "kernels/tensor.hpp"
#include "kernels/views.hpp"

namespace SMPM_NS {

// The axis the shock travels along (y): impact velocities, mirror copies, the front, the bands
// of [[regions]] and free surfaces are taken along it; the other axes are lateral.
inline constexpr int kImpactAxis = 1;

// A position [m] or a velocity [m/s], one component per axis.
using Vector = kern::Vec<kern::kDim>;
// Lattice indices (points, pixels, buckets), one per axis.
using Index = kern::Vec<kern::kDim, long>;

// An axis-aligned box [lo, hi] [m].
struct Box {
  Vector lo{}, hi{};
};

// |v|, by std::hypot (no overflow or underflow in the squares).
inline double magnitude(const Vector& v) {
  if constexpr (kern::kDim == 2) return std::hypot(v[0], v[1]);
  else return std::hypot(v[0], v[1], v[2]);
}

// Whether p lies in the closed box [lo, hi].
inline bool in_box(const Box& b, const Vector& p) {
  for (int d = 0; d < kern::kDim; ++d)
    if (!(p[d] >= b.lo[d] && p[d] <= b.hi[d])) return false;
  return true;
}

// Calls f(i) for every index i with first[d] <= i[d] <= last[d] on every axis d, axis 0 fastest
// (the last axis in the outer loop); none when a range is empty.
template <class F>
void for_each_index(const Index& first, const Index& last, F&& f) {
  for (int d = 0; d < kern::kDim; ++d)
    if (first[d] > last[d]) return;
  Index i = first;
  for (;;) {
    for (i[0] = first[0]; i[0] <= last[0]; ++i[0]) f(static_cast<const Index&>(i));
    int d = 1;
    while (d < kern::kDim && i[d] == last[d]) {
      i[d] = first[d];
      ++d;
    }
    if (d == kern::kDim) return;
    ++i[d];
  }
}

// The grid's origin [m], its lowest node.
inline Vector grid_origin(const kern::GridGeom& g) {
  Vector o;
  for (int d = 0; d < kern::kDim; ++d) o[d] = g.lo[d];
  return o;
}

// The period of each axis [m]: the grid's length along a periodic axis, 0 along the others.
inline Vector periods(const kern::GridGeom& g) {
  Vector p{};
  for (int d = 0; d < kern::kDim; ++d) p[d] = g.wrap[d] ? g.length(d) : 0.0;
  return p;
}

// Position of index i in a row-major array of n[0] x n[1] x ... entries, axis 0 fastest.
inline long linear_index(const Index& i, const Index& n) {
  long k = i[kern::kDim - 1];
  for (int d = kern::kDim - 2; d >= 0; --d) k = k * n[d] + i[d];
  return k;
}

}  // namespace SMPM_NS
