// The velocity gradient of n points in arrays of their own, for the separate gather and
// constitutive passes of the kernel tests and benchmarks (kern::g2p, kern::constitutive_update),
// and the gradient measures of one point. The engine never stores L: its last gather pass keeps
// it in a block buffer (kern::g2p_blocks).
#pragma once
#include <array>
#include <cstddef>
#include <vector>

#include "engine/diagnostics.hpp"
#include "engine/particles.hpp"
#include "kernels/views.hpp"

namespace SMPM_NS::test {

struct GradientArrays {
  std::vector<double> L[kern::kDim * kern::kDim];  // row major [1/s]
  explicit GradientArrays(std::size_t n = 0, double value = 0.0) {
    for (auto& a : L) a.assign(n, value);
  }
  kern::Gradient view() {
    kern::Gradient g;
    for (int k = 0; k < kern::kDim * kern::kDim; ++k) g.L[k] = L[k].data();
    return g;
  }
  bool operator==(const GradientArrays& o) const {
    for (int k = 0; k < kern::kDim * kern::kDim; ++k)
      if (L[k] != o.L[k]) return false;
    return true;
  }
};

// One point with the gradient measures (store_gradient_measures) of L, row major.
inline Particles point_with_measures(std::array<double, kern::kDim * kern::kDim> L) {
  Particles P;
  P.resize(1);
  kern::Gradient g;
  for (int k = 0; k < kern::kDim * kern::kDim; ++k) g.L[k] = &L[k];
  store_gradient_measures(g, 0, 1, P);
  return P;
}

}  // namespace SMPM_NS::test
