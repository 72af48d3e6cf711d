// The points of a kernel test binned by cell: keys, the sorted order and each key's first
// position (kern::sort_by_cell), for the engine's dimension.
#pragma once
#include <catch2/catch.hpp>
#include <omp.h>

#include <array>
#include <cstdint>
#include <vector>

#include "engine/particles.hpp"
#include "kernels/sort.hpp"

namespace SMPM_NS::test {

struct Bins {
  std::vector<std::uint32_t> key, order, start, hist;
};

inline Bins bin(const kern::GridGeom& g, const Particles& P) {
  Bins b;
  const std::size_t n = P.size();
  b.key.resize(n);
  b.order.resize(n);
  b.start.resize(g.num_keys() + 1);
  b.hist.resize(static_cast<std::size_t>(omp_get_max_threads()) * g.num_keys());
  std::array<const double*, kern::kDim> x;
  for (int d = 0; d < kern::kDim; ++d) x[d] = P.x[d].data();
  REQUIRE(kern::sort_by_cell(g, x.data(), n, b.key.data(), b.hist.data(), b.start.data(), b.order.data()) == -1);
  return b;
}

}  // namespace SMPM_NS::test
