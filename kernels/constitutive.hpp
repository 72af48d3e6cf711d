// Constitutive update over particle arrays. A material is an EOS part (pressure) and a
// strength part (deviatoric stress), passed as template arguments: one loop per pair, no
// virtual calls per particle. Per particle and step:
//   volume      V <- V det(I + dt L)
//   deviator    Jaumann trial step, then the strength part (elastic, radial return, none)
//   viscosity   q = rho l (c_Q l tr(D)^2 - c_L c tr(D)) in compression (optional)
//   energy      e <- e + (deviatoric work - (P_mid + q) dV) / m, time-centred; P is linear in
//               e for both EOS parts (P = cold(rho) + Gamma rho e, Gamma rho constant), so the
//               centred update is solved exactly
//   pressure    P <- EOS(rho, e)
//   signal      c_L + |v| for the next CFL step
#pragma once
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include <Eigen/Core>

#include "views.hpp"

namespace smpm::kern {

// ---- EOS parts: P(rho, e) = cold(rho) + gamma_rho() * e ------------------------------------

// Linear: P = K (rho / rho0 - 1), no energy dependence.
struct LinearEos {
  double rho0 = 1.0, K = 1.0;
  double cold(double rho) const { return K * (rho / rho0 - 1.0); }
  double gamma_rho() const { return 0.0; }
  double pressure(double rho, double /*e*/) const { return cold(rho); }
  // isentropic bulk modulus rho (dP/drho)_s
  double bulk_modulus(double /*rho*/, double /*P*/) const { return K; }
};

// Mie-Grueneisen with a linear Us-up Hugoniot (physics.md section 2), mu = rho/rho0 - 1:
//   compression  P = (C mu + D mu^2 + S mu^3)(1 - Gamma mu / 2) + Gamma rho e
//   tension      P = C mu + Gamma rho e
// C = rho0 c0^2, D = C (2 s - 1), S = C (s - 1)(3 s - 1), Gamma = gamma0 rho0 / rho.
struct MieGruneisenEos {
  double rho0 = 1.0, C = 1.0, D = 0.0, S = 0.0, gamma0 = 0.0;
  static MieGruneisenEos make(double rho0, double c0, double s, double gamma0) {
    const double C = rho0 * c0 * c0;
    return {rho0, C, C * (2.0 * s - 1.0), C * (s - 1.0) * (3.0 * s - 1.0), gamma0};
  }
  double gamma_rho() const { return gamma0 * rho0; }
  double cold(double rho) const {
    const double mu = rho / rho0 - 1.0;
    if (mu < 0.0) return C * mu;
    // Gamma mu / 2 = gamma0 (1 - rho0 / rho) / 2
    return ((S * mu + D) * mu + C) * mu * (1.0 - 0.5 * gamma0 * (1.0 - rho0 / rho));
  }
  double dcold_drho(double rho) const {
    const double mu = rho / rho0 - 1.0;
    if (mu < 0.0) return C / rho0;
    const double A = ((S * mu + D) * mu + C) * mu, dA = (3.0 * S * mu + 2.0 * D) * mu + C;
    const double B = 1.0 - 0.5 * gamma0 * (1.0 - rho0 / rho), dB = -0.5 * gamma0 * rho0 / (rho * rho);
    return dA / rho0 * B + A * dB;
  }
  double pressure(double rho, double e) const { return cold(rho) + gamma_rho() * e; }
  // rho (dP/drho)_s = rho (dP/drho)_e + (dP/de)_rho P / rho, floored at zero in deep tension
  double bulk_modulus(double rho, double P) const {
    return std::max(0.0, rho * dcold_drho(rho) + gamma_rho() * P / rho);
  }
};

// ---- strength parts --------------------------------------------------------------------------

// The in-plane deviator as an Eigen fixed-size symmetric 2x2 (s_zz = -trace follows).
using Mat2 = Eigen::Matrix2d;
inline Mat2 deviator(double sxx, double syy, double sxy) { return (Mat2() << sxx, sxy, sxy, syy).finished(); }

// Elastic trial step of the deviator: ds/dt = 2 G dev(D) + W s - s W (Jaumann), plane strain
// (D_zz = 0, s_zz = -(s_xx + s_yy)); w = W_xy = (L_xy - L_yx) / 2.
inline void jaumann_trial(double G, double& sxx, double& syy, double& sxy, double dxx, double dyy, double dxy,
                          double w, double dt) {
  const Mat2 s = deviator(sxx, syy, sxy);
  const Mat2 D = (Mat2() << dxx, dxy, dxy, dyy).finished();
  const Mat2 W = (Mat2() << 0.0, w, -w, 0.0).finished();
  // in-plane part of dev(D): the 3D deviator subtracts tr(D)/3 from every diagonal entry
  const Mat2 devD = D - (D.trace() / 3.0) * Mat2::Identity();
  const Mat2 sn = s + dt * (2.0 * G * devD + W * s - s * W);
  sxx = sn(0, 0);
  syy = sn(1, 1);
  sxy = sn(0, 1);
}

// sqrt(3 J2) of a plane-strain deviator (s_zz = -(s_xx + s_yy)).
inline double von_mises(double sxx, double syy, double sxy) {
  const Mat2 s = deviator(sxx, syy, sxy);
  const double szz = -s.trace();
  return std::sqrt(1.5 * (s.squaredNorm() + szz * szz));
}

// No shear strength: the deviator stays zero.
struct NoStrength {
  static constexpr bool plastic = false;
  double shear_modulus() const { return 0.0; }
  double update(double& sxx, double& syy, double& sxy, double, double, double, double, double, double*) const {
    sxx = syy = sxy = 0.0;
    return 0.0;
  }
};

struct ElasticStrength {
  static constexpr bool plastic = false;
  double G = 0.0;
  double shear_modulus() const { return G; }
  double update(double& sxx, double& syy, double& sxy, double dxx, double dyy, double dxy, double w, double dt,
                double*) const {
    jaumann_trial(G, sxx, syy, sxy, dxx, dyy, dxy, w, dt);
    return 0.0;
  }
};

// von Mises with linear isotropic hardening, radial return: Y = Y0 + H eps_p; a trial state with
// sqrt(3 J2) > Y flows by d_eps_p = (sqrt(3 J2) - Y) / (3 G + H) and is scaled back onto the
// hardened surface. Returns the plastic work per unit volume, Y_new d_eps_p.
struct VonMisesStrength {
  static constexpr bool plastic = true;
  double G = 0.0, Y0 = 0.0, H = 0.0;
  double shear_modulus() const { return G; }
  double update(double& sxx, double& syy, double& sxy, double dxx, double dyy, double dxy, double w, double dt,
                double* epsp) const {
    jaumann_trial(G, sxx, syy, sxy, dxx, dyy, dxy, w, dt);
    const double q = von_mises(sxx, syy, sxy);
    const double Y = Y0 + H * *epsp;
    if (q <= Y) return 0.0;
    const double deps = (q - Y) / (3.0 * G + H);
    const double Ynew = Y + H * deps;
    const double f = Ynew / q;
    sxx *= f;
    syy *= f;
    sxy *= f;
    *epsp += deps;
    return Ynew * deps;
  }
};

// ---- the update -----------------------------------------------------------------------------

// Optional per-particle state (null when the scene does not need it).
struct ConstitutiveState {
  double* e = nullptr;     // specific internal energy [J/kg]; required for an energy-dependent EOS
  double* epsp = nullptr;  // equivalent plastic strain; required for a plastic strength part
  double* q = nullptr;     // artificial viscous pressure [Pa]; null: no artificial viscosity
  double* wp = nullptr;    // plastic work per mass [J/kg]; tracked only when asked for
};

struct ConstitutiveParams {
  double dt = 0.0;
  double p_min = -1e300;      // tension cutoff [Pa]: below it the point has fractured (see below)
  double rho_min = 0.0;       // below this density [kg/m^3] a point has fractured too (debris)
  double av_length = 0.0;     // l [m], the cell size
  double av_linear = 0.0;     // c_L
  double av_quadratic = 0.0;  // c_Q
};

// Fastest signal speed of a particle: longitudinal wave speed plus |v|.
template <class Eos, class Strength>
inline double signal_speed(const Eos& eos, const Strength& str, double rho, double P, double vx, double vy) {
  const double c = std::sqrt((eos.bulk_modulus(rho, P) + 4.0 / 3.0 * str.shear_modulus()) / rho);
  return c + std::sqrt(vx * vx + vy * vy);
}

// Only particles with select[body[p]] != 0 are updated (null select: all particles).
struct Selection {
  const std::uint8_t* body = nullptr;
  const std::uint8_t* select = nullptr;
  bool operator()(std::size_t p) const { return !select || select[body[p]]; }
};

struct ConstitutiveResult {
  double max_speed = 0.0;   // max over particles of the signal speed [m/s], for the next dt
  std::ptrdiff_t bad = -1;  // lowest index of a particle whose volume became non-positive or NaN
};

template <class Eos, class Strength>
ConstitutiveResult constitutive_update(const ParticleView& P, const ConstitutiveState& S, std::size_t n,
                                       const ConstitutiveParams& q, const Eos& eos, const Strength& str,
                                       Selection sel = {}) {
  double vmax = 0.0;
  std::ptrdiff_t bad = static_cast<std::ptrdiff_t>(n);
  const double dt = q.dt, l = q.av_length;
#pragma omp parallel for schedule(static) reduction(max : vmax) reduction(min : bad)
  for (std::size_t p = 0; p < n; ++p) {
    if (!sel(p)) continue;
    const double lxx = P.Lxx[p], lxy = P.Lxy[p], lyx = P.Lyx[p], lyy = P.Lyy[p];
    const double jinc = (1.0 + dt * lxx) * (1.0 + dt * lyy) - dt * dt * lxy * lyx;
    const double V0 = P.V[p], V = V0 * jinc;
    if (!(V > 0.0)) bad = std::min(bad, static_cast<std::ptrdiff_t>(p));
    P.V[p] = V;
    const double m = P.m[p], rho = m / V;
    const double dxy = 0.5 * (lxy + lyx), w = 0.5 * (lxy - lyx), trD = lxx + lyy;
    const double a0 = P.sxx[p], b0 = P.syy[p], c0 = P.sxy[p];
    const double Wp = str.update(P.sxx[p], P.syy[p], P.sxy[p], lxx, lyy, dxy, w, dt, S.epsp ? S.epsp + p : nullptr);
    if (S.wp) S.wp[p] += Wp * V / m;
    const double P0 = P.p[p];
    double qv = 0.0, qspeed = 0.0;
    if (S.q) {
      if (trD < 0.0) {
        const double c = std::sqrt(eos.bulk_modulus(rho, P0) / rho);
        qv = rho * l * (q.av_quadratic * l * trD * trD - q.av_linear * c * trD);
        qspeed = 2.0 * q.av_quadratic * l * -trD;
      }
      S.q[p] = qv;
    }
    double Pn;
    double e_old = 0.0, w_dev = 0.0;  // for the energy of a point that fractures
    const double dV = V - V0;
    if (S.e) {
      // deviatoric work (time-centred stress, mid-step volume), then the centred pressure work
      const double sD = 0.5 * ((a0 + P.sxx[p]) * lxx + (b0 + P.syy[p]) * lyy + 2.0 * (c0 + P.sxy[p]) * dxy);
      const double cold = eos.cold(rho);
      e_old = S.e[p];
      w_dev = dt * 0.5 * (V0 + V) * sD;
      const double e = (e_old + (w_dev - (0.5 * (P0 + cold) + qv) * dV) / m) / (1.0 + 0.5 * eos.gamma_rho() * dV / m);
      S.e[p] = e;
      Pn = cold + eos.gamma_rho() * e;
    } else {
      Pn = eos.pressure(rho, 0.0);
    }
    if (Pn < q.p_min || rho < q.rho_min) {
      // fractured (spall): carries neither tension nor shear from now on; its energy takes the
      // work of the pressure it actually had (new pressure 0). The elastic shear energy held in
      // the deviator is released (lost): energy.csv shows it.
      // No artificial viscosity either: a fractured point is debris, often alone in its cells,
      // whose velocity gradient is noise; a viscous signal speed from it stalled a 2 us porous
      // run at dt = 7e-4 ns when the compaction front reached the free top and it spalled.
      Pn = 0.0;
      if (S.e) S.e[p] = e_old + (w_dev - 0.5 * P0 * dV) / m;
      if (S.q) S.q[p] = 0.0;
      P.sxx[p] = P.syy[p] = P.sxy[p] = 0.0;
      const double c = std::sqrt(eos.bulk_modulus(eos.rho0, 0.0) / eos.rho0);
      P.p[p] = Pn;
      vmax = std::max(vmax, c + std::sqrt(P.vx[p] * P.vx[p] + P.vy[p] * P.vy[p]));
      continue;
    }
    P.p[p] = Pn;
    vmax = std::max(vmax, signal_speed(eos, str, rho, Pn, P.vx[p], P.vy[p]) + qspeed);
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
    vmax = std::max(vmax, signal_speed(eos, str, P.m[p] / P.V[p], P.p[p], P.vx[p], P.vy[p]));
  }
  return vmax;
}

}  // namespace smpm::kern
