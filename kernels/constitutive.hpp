// Constitutive update over particle arrays: volume from the velocity gradient, deviatoric
// stress from a strength part (objective Jaumann rate, plane strain), pressure from an EOS part.
// Parts are plain structs passed as template arguments: one loop per (EOS, strength) pair,
// no virtual calls per particle.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "views.hpp"

namespace smpm::kern {

// Linear EOS: P = K (rho / rho0 - 1).
struct LinearEos {
  double rho0 = 1.0, K = 1.0;
  double pressure(double rho, double /*e*/) const { return K * (rho / rho0 - 1.0); }
  double bulk_modulus(double /*rho*/, double /*e*/) const { return K; }
};

// Hypoelastic deviator: ds/dt = 2 G dev(D) + W s - s W (Jaumann), plane strain (D_zz = 0),
// s_zz = -(s_xx + s_yy) since the deviator is traceless.
struct ElasticStrength {
  double G = 0.0;
  inline void update(double& sxx, double& syy, double& sxy, double dxx, double dyy, double dxy,
                     double w, double dt) const {
    const double tr3 = (dxx + dyy) / 3.0;
    const double a = sxx, b = syy, c = sxy;
    sxx = a + dt * (2.0 * G * (dxx - tr3) + 2.0 * w * c);
    syy = b + dt * (2.0 * G * (dyy - tr3) - 2.0 * w * c);
    sxy = c + dt * (2.0 * G * dxy + w * (b - a));
  }
  double shear_modulus() const { return G; }
};

// Fastest signal speed of a particle: longitudinal wave speed sqrt((K + 4G/3) / rho) plus |v|.
template <class Eos, class Strength>
inline double signal_speed(const Eos& eos, const Strength& str, double rho, double e, double vx, double vy) {
  const double c = std::sqrt((eos.bulk_modulus(rho, e) + 4.0 / 3.0 * str.shear_modulus()) / rho);
  return c + std::sqrt(vx * vx + vy * vy);
}

// Only particles with select[body[p]] != 0 are updated (null select: all particles).
struct Selection {
  const std::uint8_t* body = nullptr;
  const std::uint8_t* select = nullptr;
  bool operator()(std::size_t p) const { return !select || select[body[p]]; }
};

struct ConstitutiveResult {
  double max_speed = 0.0;   // max over particles of (c_p + |v_p|) [m/s], for the next dt
  std::ptrdiff_t bad = -1;  // lowest index of a particle whose volume became non-positive or NaN
};

template <class Eos, class Strength>
ConstitutiveResult constitutive_update(const ParticleView& P, std::size_t n, double dt, const Eos& eos,
                                       const Strength& str, Selection sel = {}) {
  double vmax = 0.0;
  std::ptrdiff_t bad = static_cast<std::ptrdiff_t>(n);
#pragma omp parallel for schedule(static) reduction(max : vmax) reduction(min : bad)
  for (std::size_t p = 0; p < n; ++p) {
    if (!sel(p)) continue;
    const double lxx = P.Lxx[p], lxy = P.Lxy[p], lyx = P.Lyx[p], lyy = P.Lyy[p];
    const double jinc = (1.0 + dt * lxx) * (1.0 + dt * lyy) - dt * dt * lxy * lyx;
    const double V = P.V[p] * jinc;
    if (!(V > 0.0)) bad = std::min(bad, static_cast<std::ptrdiff_t>(p));
    P.V[p] = V;
    const double w = 0.5 * (lxy - lyx);
    str.update(P.sxx[p], P.syy[p], P.sxy[p], lxx, lyy, 0.5 * (lxy + lyx), w, dt);
    const double rho = P.m[p] / V;
    P.p[p] = eos.pressure(rho, 0.0);
    vmax = std::max(vmax, signal_speed(eos, str, rho, 0.0, P.vx[p], P.vy[p]));
  }
  return {vmax, bad == static_cast<std::ptrdiff_t>(n) ? -1 : bad};
}

template <class Eos, class Strength>
double max_signal_speed(const ParticleView& P, std::size_t n, const Eos& eos, const Strength& str,
                        Selection sel = {}) {
  double vmax = 0.0;
#pragma omp parallel for schedule(static) reduction(max : vmax)
  for (std::size_t p = 0; p < n; ++p) {
    if (!sel(p)) continue;
    vmax = std::max(vmax, signal_speed(eos, str, P.m[p] / P.V[p], 0.0, P.vx[p], P.vy[p]));
  }
  return vmax;
}

}  // namespace smpm::kern
