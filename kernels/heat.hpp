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
#include <cstddef>
#include <cstdint>

#include "transfer.hpp"
#include "grid_update.hpp"
#include "views.hpp"

namespace smpm::kern {

struct HeatGrid {
  double* cap;   // C_i [J/(K m)]
  double* capT;  // S_i, then scratch
  double* T;     // nodal temperature S_i / C_i [K] (0 where C_i = 0)
  double* dT;    // temperature change this step [K]
};

struct HeatParticles {
  const double* x; const double* y; const double* m;
  const double* T;          // temperature [K]
  const std::uint8_t* body;
  const double* cv_body;    // specific heat per body [J/(kg K)]
  double* e;                // specific internal energy [J/kg]
};

template <class Shape>
void heat_scatter(const GridGeom& g, const HeatGrid& H, const HeatParticles& P, const std::uint32_t* order,
                  const std::uint32_t* cell_start, double lp) {
  const double inv_h = 1.0 / g.h;
  for_each_tile_colored<2>(
      g, cell_start,
      [&](const TileBlock& blk, std::uint32_t s0, std::uint32_t s1) {
        for (std::uint32_t s = s0; s < s1; ++s) {
          const std::uint32_t p = order[s];
          constexpr int N = Shape::N;
          double wx[N], wy[N], dwx[N], dwy[N];
          const double xg = (P.x[p] - g.x0) * inv_h, yg = (P.y[p] - g.y0) * inv_h;
          const int bx = Shape::eval(xg, lp, wx, dwx), by = Shape::eval(yg, lp, wy, dwy);
          const double c = P.m[p] * P.cv_body[P.body[p]], cT = c * P.T[p];
          for (int b = 0; b < N; ++b) {
            double* row = blk.s + 2 * ((by + b - blk.j0) * blk.span + (bx - blk.i0));
            for (int a = 0; a < N; ++a) {
              const double w = wx[a] * wy[b];
              row[2 * a] += w * c;
              row[2 * a + 1] += w * cT;
            }
          }
        }
      },
      [&](const double* v, std::size_t n, int) {
        H.cap[n] += v[0];
        H.capT[n] += v[1];
      });
}

// Nodal temperature change; nodes outside the conducting set get dT = 0.
void heat_conduct(const GridGeom& g, const HeatGrid& H, double conductivity, double c_min, double dt);

template <class Shape>
void heat_gather(const GridGeom& g, const HeatGrid& H, const HeatParticles& P, std::size_t n, double lp,
                 double phi) {
  const double inv_h = 1.0 / g.h;
#pragma omp parallel for schedule(static)
  for (std::size_t p = 0; p < n; ++p) {
    constexpr int N = Shape::N;
    double wx[N], wy[N], dwx[N], dwy[N];
    const double xg = (P.x[p] - g.x0) * inv_h, yg = (P.y[p] - g.y0) * inv_h;
    const int bx = Shape::eval(xg, lp, wx, dwx), by = Shape::eval(yg, lp, wy, dwy);
    double dT = 0.0, T = 0.0;
    for (int b = 0; b < N; ++b) {
      const std::size_t row = g.node(bx, by + b);
      for (int a = 0; a < N; ++a) {
        const double w = wx[a] * wy[b];
        dT += w * H.dT[row + a];
        T += w * H.T[row + a];
      }
    }
    P.e[p] += P.cv_body[P.body[p]] * (dT + phi * (T - P.T[p]));
  }
}

}  // namespace smpm::kern
