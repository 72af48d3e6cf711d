// Heat conduction on the background grid, explicit, energy-conserving:
//   scatter  C_i = sum_p w_ip m_p cv_p,  S_i = sum_p w_ip m_p cv_p T_p      (colored)
//   conduct  on nodes with C_i >= c_min (enough material to carry heat): T_i = S_i / C_i,
//            Q_i = k sum_{j in 4 neighbours, C_j >= c_min} (T_j - T_i)   [W per metre thickness]
//            (Fourier flux k dT/h through a face of length h), dT_i = dt Q_i / C_i
//   gather   e_p += cv_p (sum_i w_ip dT_i + phi (sum_i w_ip T_i - T_p))
// Fluxes are antisymmetric, so sum_i C_i dT_i = 0: the gather adds exactly zero energy in total.
// The grid sees only the interpolated part of the particle temperatures; a particle's deviation
// from it (sub-cell structure, e.g. plastic heating at one point) would never conduct under the
// increment alone. The second term relaxes it towards the grid field, phi = dt / tau with
// tau = 10 h^2 / alpha: slow against grid-scale diffusion, because the same term also smooths
// resolved fields (a full PIC projection every step at the conduction limit diffuses 2-3 times
// too fast; at this rate the excess is about 2 %, tests/test_heat.cpp). With equal cv it sums
// to zero energy (sum_p m cv sum_i w T_i = sum_i C_i T_i = sum_p m cv T_p).
// Nodes below c_min (free surfaces, void faces) are insulating, which keeps the explicit step
// stable for dt <= c_min / (4 k).
#pragma once
#include "dimension.hpp"
#include <cstddef>
#include <cstdint>

#include "transfer.hpp"
#include "grid_update.hpp"
#include "views.hpp"

namespace SMPM_NS::kern {

struct HeatGrid {
  double* cap;   // C_i [J/(K m)]
  double* capT;  // S_i, then scratch
  double* T;     // nodal temperature S_i / C_i [K] (0 where C_i = 0)
  double* dT;    // temperature change this step [K]
};

struct HeatParticles {
  const double* pos[kDim];  // position [m]
  const double* m;
  const double* T;          // temperature [K]
  const std::uint8_t* body;
  const double* cv_body;    // specific heat per body [J/(kg K)]
  double* e;                // specific internal energy [J/kg]
};

// The point's stencil (x - origin) * (1 / h) per axis, as the transfers form it.
template <class Shape>
SMPM_INLINE Stencil<Shape, kDim> heat_stencil(const GridGeom& g, const HeatParticles& P, std::size_t p, double lp) {
  const double inv_h = 1.0 / g.h;
  Vec<kDim> u;
  for (int d = 0; d < kDim; ++d) u[d] = (P.pos[d][p] - g.origin(d)) * inv_h;
  return Stencil<Shape, kDim>(u, lp);
}

template <class Shape>
void heat_scatter(const GridGeom& g, const HeatGrid& H, const HeatParticles& P, const std::uint32_t* order,
                  const std::uint32_t* cell_start, double lp) {
  for_each_tile_colored<2>(
      g, cell_start,
      [&](const TileBlock& blk, std::uint32_t s0, std::uint32_t s1) {
        const TileSink<2> sink{{blk.s}, blk.lo, blk.span};
        for (std::uint32_t s = s0; s < s1; ++s) {
          const std::uint32_t p = order[s];
          const auto st = heat_stencil<Shape>(g, P, p, lp);
          const double c = P.m[p] * P.cv_body[P.body[p]], cT = c * P.T[p];
          const std::size_t first = sink.node(node_of(st, Idx<kDim>{}));
          st.for_each_by_line([&](const Idx<kDim>& a, int) {
            double* v = blk.s + 2 * node_index(sink, first, a);
            const double w = st.weight(a);
            v[0] += w * c;
            v[1] += w * cT;
          });
        }
      },
      [&](const double* v, std::size_t n, int) {
        H.cap[n] += v[0];
        H.capT[n] += v[1];
      });
}

// Nodal temperatures T_i = S_i / C_i (0 where C_i = 0) on every node, ghosts included.
void heat_temperatures(const GridGeom& g, const HeatGrid& H);
// Nodal temperature change from the fluxes between axis neighbours (ghosts filled: the caller's
// halo phase); nodes outside the conducting set get dT = 0. capT becomes the heat power Q_i.
void heat_conduct(const GridGeom& g, const HeatGrid& H, double conductivity, double c_min, double dt);

template <class Shape>
void heat_gather(const GridGeom& g, const HeatGrid& H, const HeatParticles& P, std::size_t n, double lp,
                 double phi) {
#pragma omp parallel for schedule(static)
  for (std::size_t p = 0; p < n; ++p) {
    const auto st = heat_stencil<Shape>(g, P, p, lp);
    double dT = 0.0, T = 0.0;
    const std::size_t first = g.node(node_of(st, Idx<kDim>{}));
    st.for_each([&](const Idx<kDim>& a, int) {
      const std::size_t k = node_index(g, first, a);
      const double w = st.weight(a);
      dT += w * H.dT[k];
      T += w * H.T[k];
    });
    P.e[p] += P.cv_body[P.body[p]] * (dT + phi * (T - P.T[p]));
  }
}

}  // namespace SMPM_NS::kern
