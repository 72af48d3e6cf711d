#include "heat.hpp"

namespace smpm::kern {

void heat_conduct(const GridGeom& g, const HeatGrid& H, double k, double c_min, double dt) {
  const int i0 = g.periodic_x ? 0 : -g.pad, i1 = g.periodic_x ? g.nx - 1 : g.nx + g.pad;
  const int j0 = -g.pad, j1 = g.ny + g.pad;
  // nodal temperatures first (a separate pass: every flux needs both ends)
#pragma omp parallel for schedule(static)
  for (int j = j0; j <= j1; ++j)
    for (int i = -g.pad; i <= g.nx + g.pad; ++i) {
      H.dT[g.node(i, j)] = 0.0;
      const std::size_t n = g.node(i, j);
      H.T[n] = H.cap[n] > 0.0 ? H.capT[n] / H.cap[n] : 0.0;
    }
  // periodic: ghost columns carry the temperatures of the columns they stand for
  if (g.periodic_x) {
#pragma omp parallel for schedule(static)
    for (int j = j0; j <= j1; ++j) {
      for (int i = -g.pad; i < 0; ++i) {
        H.T[g.node(i, j)] = H.T[g.node(i + g.nx, j)];
        H.cap[g.node(i, j)] = H.cap[g.node(i + g.nx, j)];
      }
      for (int i = g.nx; i <= g.nx + g.pad; ++i) {
        H.T[g.node(i, j)] = H.T[g.node(i - g.nx, j)];
        H.cap[g.node(i, j)] = H.cap[g.node(i - g.nx, j)];
      }
    }
  }
  // fluxes into capT (reused as the heat power Q_i)
#pragma omp parallel for schedule(static)
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      const std::size_t n = g.node(i, j);
      double Q = 0.0;
      if (H.cap[n] >= c_min) {
        const double T = H.T[n];
        const std::size_t nb[4] = {i > -g.pad ? n - 1 : n, i < g.nx + g.pad ? n + 1 : n,
                                   j > j0 ? n - g.sx() : n, j < j1 ? n + g.sx() : n};
        for (std::size_t m : nb)
          if (m != n && H.cap[m] >= c_min) Q += k * (H.T[m] - T);
      }
      H.capT[n] = Q;
    }
#pragma omp parallel for schedule(static)
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      const std::size_t n = g.node(i, j);
      H.dT[n] = H.cap[n] >= c_min ? dt * H.capT[n] / H.cap[n] : 0.0;
    }
  if (g.periodic_x) {
    double* a[] = {H.dT};  // (T's ghosts were filled above)
    fill_periodic_ghosts(g, g.all_nodes(), a, 1);
  }
}

}  // namespace smpm::kern
