#include "dimension.hpp"
#include "heat.hpp"

namespace SMPM_NS::kern {

void heat_temperatures(const GridGeom& g, const HeatGrid& H) {
  const NodeBox all = g.all_nodes();
  const int lines = all.lines(), len = all.hi[0] - all.lo[0] + 1;
#pragma omp parallel for schedule(static)
  for (int r = 0; r < lines; ++r) {
    const std::size_t n0 = g.node(all.line_start(r));
    for (int i = 0; i < len; ++i) {
      const std::size_t n = n0 + static_cast<std::size_t>(i);
      H.dT[n] = 0.0;
      H.T[n] = H.cap[n] > 0.0 ? H.capT[n] / H.cap[n] : 0.0;
    }
  }
}

void heat_conduct(const GridGeom& g, const HeatGrid& H, double k, double c_min, double dt) {
  const NodeBox all = g.all_nodes(), b = real_nodes(g, all);
  // fluxes into capT (reused as the heat power Q_i): the two neighbours along each axis, the
  // low one first, where they exist in the storage
  for_each_node_by_line(g, b, [&](const Idx<kDim>& i, std::size_t n) {
    double Q = 0.0;
    if (H.cap[n] >= c_min) {
      const double T = H.T[n];
      for (int d = 0; d < kDim; ++d) {
        const std::size_t s = g.stride(d);
        const std::size_t nb[2] = {i[d] > all.lo[d] ? n - s : n, i[d] < all.hi[d] ? n + s : n};
        for (std::size_t m : nb)
          if (m != n && H.cap[m] >= c_min) Q += k * (H.T[m] - T);
      }
    }
    H.capT[n] = Q;
  });
  for_each_node_by_line(g, b, [&](const Idx<kDim>&, std::size_t n) {
    H.dT[n] = H.cap[n] >= c_min ? dt * H.capT[n] / H.cap[n] : 0.0;
  });
}

}  // namespace SMPM_NS::kern
