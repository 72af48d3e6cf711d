// Constitutive update over particle arrays. A material is an EOS part (pressure) and a
// strength part (deviatoric stress), passed as template arguments: one loop per pair, no
// virtual calls per particle. Per particle and step:
//   volume      V <- V det(I + dt L)
//   deviator    Jaumann trial step, then the strength part (elastic, radial return with an
//               optional flow viscosity, none)
//   viscosity   q = rho l (c_Q l tr(D)^2 - c_L c tr(D)) in compression (optional)
//   energy      mid-step L: e <- e + dt V0 sigma_old : D / m, sigma_old = s - (P + q) I the
//               stress the scatter used: exactly the work of the internal forces over the
//               grid's mid-step velocity (kern::g2p_particle), so the step conserves energy;
//               updated L: e <- e + (deviatoric work - (P_mid + q) dV) / m, time-centred
//   pressure    P <- EOS(rho, e)
//   signal      c_L + |v| for the next CFL step
#pragma once
#include "dimension.hpp"
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <utility>

#include "views.hpp"

namespace SMPM_NS::kern {

// ---- EOS parts: P(rho, e) = cold(rho) + gamma_rho() * e ------------------------------------

// Linear: P = K (rho / rho0 - 1), no energy dependence.
struct LinearEos {
  static constexpr bool needs_energy = false;
  double rho0 = 1.0, K = 1.0;
  SMPM_INLINE double cold(double rho) const { return K * (rho / rho0 - 1.0); }
  double gamma_rho() const { return 0.0; }
  SMPM_INLINE double pressure(double rho, double /*e*/) const { return cold(rho); }
  // isentropic bulk modulus rho (dP/drho)_s
  SMPM_INLINE double bulk_modulus(double /*rho*/, double /*P*/) const { return K; }
};

// Mie-Grueneisen with a linear Us-up Hugoniot (docs/model.md, "Equation of state"),
// mu = rho/rho0 - 1:
//   compression  P = (C mu + D mu^2 + S mu^3)(1 - Gamma mu / 2) + Gamma rho e
//   tension      P = C mu + Gamma rho e
// C = rho0 c0^2, D = C (2 s - 1), S = C (s - 1)(3 s - 1), Gamma = gamma0 rho0 / rho.
struct MieGruneisenEos {
  static constexpr bool needs_energy = true;  // P depends on e: the state must carry e
  double rho0 = 1.0, C = 1.0, D = 0.0, S = 0.0, gamma0 = 0.0;
  static MieGruneisenEos make(double rho0, double c0, double s, double gamma0) {
    const double C = rho0 * c0 * c0;
    return {rho0, C, C * (2.0 * s - 1.0), C * (s - 1.0) * (3.0 * s - 1.0), gamma0};
  }
  double gamma_rho() const { return gamma0 * rho0; }
  // Both branches are computed and one selected: the particle loop stays branch-free.
  SMPM_INLINE double cold(double rho) const {
    const double mu = rho / rho0 - 1.0;
    // Gamma mu / 2 = gamma0 (1 - rho0 / rho) / 2
    const double comp = ((S * mu + D) * mu + C) * mu * (1.0 - 0.5 * gamma0 * (1.0 - rho0 / rho));
    return mu < 0.0 ? C * mu : comp;
  }
  SMPM_INLINE double dcold_drho(double rho) const {
    const double mu = rho / rho0 - 1.0;
    const double A = ((S * mu + D) * mu + C) * mu, dA = (3.0 * S * mu + 2.0 * D) * mu + C;
    const double B = 1.0 - 0.5 * gamma0 * (1.0 - rho0 / rho), dB = -0.5 * gamma0 * rho0 / (rho * rho);
    const double tension = C / rho0, compression = dA / rho0 * B + A * dB;  // no division in a branch
    return mu < 0.0 ? tension : compression;
  }
  SMPM_INLINE double pressure(double rho, double e) const { return cold(rho) + gamma_rho() * e; }
  // Density at zero pressure for the specific internal energy e [J/kg], from the tension
  // branch: rho0 (1 - Gamma rho0 e / C), below rho0 for a heated point (thermal expansion);
  // rho0 for e <= 0.
  double zero_pressure_density(double e) const { return rho0 * (1.0 - gamma_rho() * std::max(e, 0.0) / C); }
  // rho (dP/drho)_s = rho (dP/drho)_e + (dP/de)_rho P / rho, floored at zero in deep tension
  SMPM_INLINE double bulk_modulus(double rho, double P) const {
    return std::max(0.0, rho * dcold_drho(rho) + gamma_rho() * P / rho);
  }
};

// ---- strength parts --------------------------------------------------------------------------

// A strength part maps the deviator s of a point over one step to the updated one:
//   StrengthResult<D> update(Sym<D> s, StrainRate<D> k, double dt, StrengthState st) const
// D-generic kinematics (the rate of deformation and the spin) and a state with slots for the
// plastic strain, the temperature and the strain rate; everything by value (a pointer to a
// local or an output reference passed into the inlined update keeps GCC 12's particle loop
// scalar). `plastic` says whether the part reads and writes st.epsp and returns plastic work.

// The rate of deformation D = sym(L) and the spin W = (L - L^T) / 2 of a step.
template <int D>
struct StrainRate {
  Sym<D> d;
  Spin<D> w;
};

// The point state a strength part reads: the constitutive loop fills epsp for a plastic part;
// T and rate are slots for temperature- and rate-dependent parts.
struct StrengthState {
  double epsp = 0.0;  // equivalent plastic strain [-]
  double T = 0.0;     // temperature [K]
  double rate = 0.0;  // equivalent strain rate [1/s]
};

template <int D>
struct StrengthResult {
  Sym<D> s;            // the updated deviator [Pa]
  StrengthState st;    // the updated state
  double work = 0.0;   // plastic work per unit volume [J/m^3]
};

// each<N>(f): f(std::integral_constant<int, 0>{}), ..., f(std::integral_constant<int, N - 1>{}).
// The per-point loops over axes and components: with the index a compile-time constant in each
// call, a point's small aggregates stay in registers (a loop index into a local array put it on
// the stack, and GCC 12 then kept the particle loop scalar).
template <int N, class F>
SMPM_INLINE void each(F&& f) {
  [&]<int... I>(std::integer_sequence<int, I...>) __attribute__((always_inline)) {
    (f(std::integral_constant<int, I>{}), ...);
  }(std::make_integer_sequence<int, N>{});
}

// Entry (A, B) of a symmetric tensor; W_AB of a spin (A != B).
template <int A, int B, int D>
SMPM_INLINE double entry(const Sym<D>& s) {
  constexpr int k = sym_index(D, A, B);
  return s[k];
}
template <int A, int B, int D>
SMPM_INLINE double spin_at(const Spin<D>& w) {
  constexpr int k = sym_index(D, A, B) - D;
  if constexpr (A < B) return w[k];
  else return -w[k];
}

// tr(s), summed in axis order.
template <int D>
SMPM_INLINE double trace(const Sym<D>& s) {
  double t = s[0];
  each<D - 1>([&](auto d) __attribute__((always_inline)) { t += s[d + 1]; });
  return t;
}

// The rate of deformation and the spin of a velocity gradient, each entry 0.5 (L_ab +- L_ba)
// (the diagonal L_aa itself).
template <int D>
SMPM_INLINE StrainRate<D> strain_rate(const Mat<D>& L) {
  StrainRate<D> k;
  each<Sym<D>::K>([&](auto i) __attribute__((always_inline)) {
    constexpr int a = sym_row(D, i), b = sym_col(D, i);
    if constexpr (a == b) {
      k.d[i] = L(a, a);
    } else {
      k.d[i] = 0.5 * (L(a, b) + L(b, a));
      k.w[i - D] = 0.5 * (L(a, b) - L(b, a));
    }
  });
  return k;
}

// Component K = (a, b) of the corotational rate W s - s W of a symmetric s:
//   a == b   sum_{c != a} 2 W_ac s_ac
//   a != b   W_ab (s_bb - s_aa) + sum_{c != a, b} (W_ac s_cb + W_bc s_ac)
// At D = 2, W = [0 w; -w 0]: 2 w s_xy, -2 w s_xy and w (s_yy - s_xx).
template <int K, int D>
SMPM_INLINE double corotation(const Sym<D>& s, const Spin<D>& w) {
  constexpr int a = sym_row(D, K), b = sym_col(D, K);
  if constexpr (a == b) {
    constexpr int c0 = a == 0 ? 1 : 0;  // the sum starts from its first term
    double r = 2.0 * spin_at<a, c0>(w) * entry<a, c0>(s);
    each<D>([&](auto c) __attribute__((always_inline)) {
      if constexpr (c != a && c != c0) r += 2.0 * spin_at<a, c>(w) * entry<a, c>(s);
    });
    return r;
  } else {
    double r = spin_at<a, b>(w) * (entry<b, b>(s) - entry<a, a>(s));
    each<D>([&](auto c) __attribute__((always_inline)) {
      if constexpr (c != a && c != b) r += spin_at<a, c>(w) * entry<c, b>(s) + spin_at<b, c>(w) * entry<a, c>(s);
    });
    return r;
  }
}

// Elastic trial step of the deviator: ds/dt = 2 G dev(D) + W s - s W (Jaumann). dev(D)
// subtracts tr(D) / 3 from each diagonal entry: at D = 2 (plane strain, D_zz = 0) the in-plane
// part of the 3D deviator, whose out-of-plane entry s_zz = -(s_xx + s_yy) is the trace-free
// closure (tests/test_material.cpp checks the step against the matrix expression in Eigen).
// Scalars, not Eigen temporaries: inside the particle loop GCC 12 kept Eigen matrices as stack
// temporaries (docs/performance.md).
template <int D>
SMPM_INLINE Sym<D> jaumann_trial(double G, Sym<D> s, StrainRate<D> k, double dt) {
  const double third_tr = trace(k.d) / 3.0, g2 = 2.0 * G;
  Sym<D> n;
  each<Sym<D>::K>([&](auto i) __attribute__((always_inline)) {
    const double rot = corotation<i>(s, k.w);
    if constexpr (i < D) n[i] = s[i] + dt * (g2 * (k.d[i] - third_tr) + rot);
    else n[i] = s[i] + dt * (g2 * k.d[i] + rot);
  });
  return n;
}

// sqrt(3 J2) of a deviator; at D = 2 with the out-of-plane entry s_zz = -(s_xx + s_yy).
template <int D>
SMPM_INLINE double von_mises(Sym<D> s) {
  double sum = s[0] * s[0];
  each<Sym<D>::K - 1>([&](auto j) __attribute__((always_inline)) {
    constexpr int k = j + 1;
    if constexpr (k < D) sum += s[k] * s[k];
    else sum += 2.0 * s[k] * s[k];
  });
  if constexpr (D == 2) {
    const double closure = -(s[0] + s[1]);  // the out-of-plane entry
    sum += closure * closure;
  }
  return std::sqrt(1.5 * sum);
}

// No shear strength: the deviator stays zero.
struct NoStrength {
  static constexpr bool plastic = false;
  double shear_modulus() const { return 0.0; }
  template <int D>
  SMPM_INLINE StrengthResult<D> update(Sym<D>, StrainRate<D>, double, StrengthState st) const {
    return {Sym<D>{}, st, 0.0};
  }
};

struct ElasticStrength {
  static constexpr bool plastic = false;
  double G = 0.0;
  double shear_modulus() const { return G; }
  template <int D>
  SMPM_INLINE StrengthResult<D> update(Sym<D> s, StrainRate<D> k, double dt, StrengthState st) const {
    return {jaumann_trial(G, s, k, dt), st, 0.0};
  }
};

// von Mises with linear isotropic hardening and an optional linear flow viscosity (Bingham):
// the flow stress is Y0 + H eps_p + 3 eta d(eps_p)/dt, eta the shear viscosity of the flowing
// material [Pa s] (3 eta: the von Mises stress of a Newtonian flow s = 2 eta D is 3 eta times its
// equivalent strain rate). Radial return, backward Euler: a trial state with sqrt(3 J2) > Y
// (Y = Y0 + H eps_p) flows by d_eps_p = (sqrt(3 J2) - Y) / (3 G + H + 3 eta / dt) and is scaled
// back onto the flow stress Y + (H + 3 eta / dt) d_eps_p. The work is the plastic work per unit
// volume, that flow stress times d_eps_p (the viscous part is dissipated too). eta = 0: the
// rate-independent law, bitwise.
struct VonMisesStrength {
  static constexpr bool plastic = true;
  double G = 0.0, Y0 = 0.0, H = 0.0;
  double eta = 0.0;  // flow viscosity [Pa s]
  double shear_modulus() const { return G; }
  template <int D>
  SMPM_INLINE StrengthResult<D> update(Sym<D> s, StrainRate<D> k, double dt, StrengthState st) const {
    Sym<D> t = jaumann_trial(G, s, k, dt);
    const double q = von_mises(t);
    const double Y = Y0 + H * st.epsp;
    const double Hv = eta > 0.0 ? H + 3.0 * eta / dt : H;  // the slope of the flow stress in d_eps_p
    // branch-free: an elastic step has deps = 0 and f = 1; the divisions are computed for every
    // point (a division inside a conditional keeps GCC from if-converting the loop)
    const bool flows = q > Y;
    const double deps_flow = (q - Y) / (3.0 * G + Hv);
    const double deps = flows ? deps_flow : 0.0;
    const double Ynew = Y + Hv * deps;
    const double ratio = Ynew / (flows ? q : 1.0);
    const double f = flows ? ratio : 1.0;
    each<Sym<D>::K>([&](auto i) __attribute__((always_inline)) { t[i] *= f; });
    st.epsp += deps;
    return {t, st, Ynew * deps};
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
  // L is the gather's mid-step one (kern::G2PParams::mid = 0.5): the energy takes the work of
  // the old stress, dt V0 sigma_old : D, which balances the grid's kinetic energy exactly; else
  // the time-centred update (see constitutive_range)
  bool midstep = false;
};

// Fastest signal speed of a particle: longitudinal wave speed plus |v|, v2 = |v|^2.
template <class Eos, class Strength>
SMPM_INLINE double signal_speed(const Eos& eos, const Strength& str, double rho, double P, double v2) {
  const double c = std::sqrt((eos.bulk_modulus(rho, P) + 4.0 / 3.0 * str.shear_modulus()) / rho);
  return c + std::sqrt(v2);
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
  // the result of two sets of points together (max and min: the order of merging does not matter)
  void merge(const ConstitutiveResult& o) {
    max_speed = std::max(max_speed, o.max_speed);
    if (o.bad >= 0 && (bad < 0 || o.bad < bad)) bad = o.bad;
  }
};

// ---- steps of the update of one point (constitutive_range) ---------------------------------

// det(I + dt L): the volume ratio of the step.
template <int D>
SMPM_INLINE double volume_ratio(Mat<D> L, double dt) {
  static_assert(D == 2 || D == 3, "two or three axes");
  if constexpr (D == 2) {
    return (1.0 + dt * L(0, 0)) * (1.0 + dt * L(1, 1)) - dt * dt * L(0, 1) * L(1, 0);
  } else {
    Mat<D> A;
    each<D * D>([&](auto i) __attribute__((always_inline)) {
      constexpr int r = i / D, c = i % D;
      A(r, c) = (r == c ? 1.0 : 0.0) + dt * L(r, c);
    });
    return A(0, 0) * (A(1, 1) * A(2, 2) - A(1, 2) * A(2, 1)) - A(0, 1) * (A(1, 0) * A(2, 2) - A(1, 2) * A(2, 0)) +
           A(0, 2) * (A(1, 0) * A(2, 1) - A(1, 1) * A(2, 0));
  }
}

// s : d of two symmetric tensors (each off-diagonal entry counted twice), in component order.
template <int D>
SMPM_INLINE double contract(Sym<D> s, Sym<D> d) {
  double r = s[0] * d[0];
  each<Sym<D>::K - 1>([&](auto j) __attribute__((always_inline)) {
    constexpr int k = j + 1;
    if constexpr (k < D) r += s[k] * d[k];
    else r += 2.0 * s[k] * d[k];
  });
  return r;
}

// A point's state at the start of the step, read from the range's arrays.
template <int D>
struct PointIn {
  Mat<D> L;      // velocity gradient (the updated one)
  Sym<D> dmid;   // mid-step rate of deformation (Midstep only)
  Sym<D> s;      // deviator
  double v2;     // |v|^2
  double m, V0, P0;
  double e0 = 0.0, q0 = 0.0;  // energy, viscous pressure (when tracked)
  StrengthState st;           // plastic strain (plastic strength parts)
};

// The arrays of a range of points: copies of the views, which the stores of the particle loop
// cannot alias (read through the caller's references, GCC reloads the pointers for every point
// and keeps the loop scalar). Point first + p of the particles; L.at(r, c)[p] its gradient.
struct RangeArrays {
  ParticleView P;
  ConstitutiveState S;
  Gradient L;
  Selection sel;
  std::size_t first;
};

template <bool HasE, bool HasQ, bool Plastic, bool Midstep, int D>
SMPM_INLINE PointIn<D> load_point(const RangeArrays& A, std::size_t p) {
  const std::size_t i = A.first + p;
  PointIn<D> in;
  each<D * D>([&](auto rc) __attribute__((always_inline)) {
    constexpr int r = rc / D, c = rc % D;
    in.L(r, c) = A.L.at(r, c)[p];
  });
  each<Sym<D>::K>([&](auto k) __attribute__((always_inline)) {
    in.s[k] = A.P.s[k][i];
    if constexpr (Midstep) in.dmid[k] = A.L.work(k)[p];
  });
  in.v2 = A.P.v[0][i] * A.P.v[0][i];
  each<D - 1>([&](auto d) __attribute__((always_inline)) { in.v2 += A.P.v[d + 1][i] * A.P.v[d + 1][i]; });
  in.m = A.P.m[i];
  in.V0 = A.P.V[i];
  in.P0 = A.P.p[i];
  if constexpr (HasE) in.e0 = A.S.e[i];
  if constexpr (HasQ) in.q0 = A.S.q[i];
  if constexpr (Plastic) in.st.epsp = A.S.epsp[i];
  return in;
}

// The viscous pressure q = rho l (c_Q l tr(D)^2 - c_L c tr(D)) in compression, and the signal
// speed it adds, 2 c_Q l |tr(D)|.
struct Viscosity {
  double q = 0.0, speed = 0.0;
};
template <class Eos>
SMPM_INLINE Viscosity viscosity(const Eos& eos, ConstitutiveParams prm, double rho, double P0, double trD) {
  const double l = prm.av_length, cQ = prm.av_quadratic, cL = prm.av_linear;
  const double c = std::sqrt(eos.bulk_modulus(rho, P0) / rho);
  const bool comp = trD < 0.0;
  return {comp ? rho * l * (cQ * l * trD * trD - cL * c * trD) : 0.0, comp ? 2.0 * cQ * l * -trD : 0.0};
}

// The energy with the mid-step rate: the work of the stress the scatter used (deviator, pressure
// and viscous pressure at the start of the step, volume V0) over the step's mid-step rate,
// dt V0 sigma : D_mid. It is exactly minus the work of the internal forces on the grid,
// dt f_i . v_i with the mid-step velocity the gather formed D_mid from (kern::g2p_particle):
// kinetic plus internal energy is conserved by the step. The volume, the deviator and the
// viscosity take the updated L (symplectic; with D_mid there too round-off grew without bound
// in thin ligaments, docs/method.md). A point that fractures takes the work of the stress it
// had, this same one.
template <int D>
SMPM_INLINE double midstep_energy(PointIn<D> in, double dt) {
  const double sD = contract(in.s, in.dmid) - (in.P0 + in.q0) * trace(in.dmid);
  return in.e0 + dt * in.V0 * sD / in.m;
}

// The energy with the updated L (q.midstep false): deviatoric work with the time-centred stress
// and mid-step volume, pressure work with P at mid-step, solved exactly (P is linear in e:
// P = cold(rho) + Gamma rho e, Gamma rho constant); a point that fractures takes the work of
// the stress it had, the centred mean of the old stress and zero (not the trial deviator, which
// never acts: with it, expanding debris gained energy without bound).
template <class Eos, int D>
SMPM_INLINE double centred_energy(const Eos& eos, ConstitutiveParams prm, PointIn<D> in, Sym<D> s1, Sym<D> d,
                                  double V, double rho, double cold, double qv) {
  const double V0 = in.V0, m = in.m, dt = prm.dt, dV = V - V0;
  Sym<D> sc;
  each<Sym<D>::K>([&](auto k) __attribute__((always_inline)) { sc[k] = in.s[k] + s1[k]; });
  const double sDc = 0.5 * contract(sc, d);
  const double e_c = (in.e0 + (dt * 0.5 * (V0 + V) * sDc - (0.5 * (in.P0 + cold) + qv) * dV) / m) /
                     (1.0 + 0.5 * eos.gamma_rho() * dV / m);
  const double sD_fr = 0.5 * contract(in.s, d);
  const double e_fr = in.e0 + (dt * 0.5 * (V0 + V) * sD_fr - 0.5 * in.P0 * dV) / m;
  const bool fr = (cold + eos.gamma_rho() * e_c < prm.p_min) | (rho < prm.rho_min);
  return fr ? e_fr : e_c;
}

// The new energy (zero when not tracked) and pressure P = EOS(rho, e).
struct EnergyPressure {
  double e = 0.0, P = 0.0;
};
template <bool HasE, bool Midstep, class Eos, int D>
SMPM_INLINE EnergyPressure energy_pressure(const Eos& eos, ConstitutiveParams prm, PointIn<D> in, Sym<D> s1,
                                           Sym<D> d, double V, double rho, double qv) {
  if constexpr (HasE) {
    const double cold = eos.cold(rho);
    double e;
    if constexpr (Midstep) e = midstep_energy(in, prm.dt);
    else e = centred_energy(eos, prm, in, s1, d, V, rho, cold, qv);
    return {e, cold + eos.gamma_rho() * e};
  } else {
    return {0.0, eos.pressure(rho, 0.0)};
  }
}

// ---- the loop -------------------------------------------------------------------------------

// The volume of point p of the range after the step.
SMPM_INLINE double step_volume(const RangeArrays& A, std::size_t p, const ConstitutiveParams& prm) {
  constexpr int D = kDim;
  Mat<D> L;
  each<D * D>([&](auto rc) __attribute__((always_inline)) {
    constexpr int r = rc / D, c = rc % D;
    L(r, c) = A.L.at(r, c)[p];
  });
  const double jinc = volume_ratio(L, prm.dt), V0 = A.P.V[A.first + p], m = A.P.m[A.first + p];
  return V0 * ((m < prm.rho_min * V0) ? std::min(jinc, 1.0) : jinc);
}

// The update of point p of the range, V its new volume (step_volume), its state loaded, updated
// and stored back (if `on`, else kept); its signal speed, 0 unless `on`. A function of its own:
// the point's aggregates are its locals, not the simd loop's (GCC 12 makes aggregates of the
// loop body per-lane stack arrays, and keeps the loop scalar).
template <bool HasE, bool HasQ, bool HasWp, bool Midstep, class Eos, class Strength>
SMPM_INLINE double update_point(const RangeArrays& A, std::size_t p, bool on, double V, const ConstitutiveParams& prm,
                                const Eos& eos, const Strength& str, double c_fractured) {
  constexpr int D = kDim;
  const std::size_t i = A.first + p;
  const PointIn<D> in = load_point<HasE, HasQ, Strength::plastic, Midstep, D>(A, p);
  const double rho = in.m / V;
  const StrainRate<D> k = strain_rate(in.L);
  const StrengthResult<D> sr = str.update(in.s, k, prm.dt, in.st);
  Viscosity visc;
  if constexpr (HasQ) visc = viscosity(eos, prm, rho, in.P0, trace(k.d));
  const EnergyPressure ep = energy_pressure<HasE, Midstep>(eos, prm, in, sr.s, k.d, V, rho, visc.q);
  const bool fractured = (ep.P < prm.p_min) | (rho < prm.rho_min);
  const double vabs = std::sqrt(in.v2);
  const double sig = fractured ? c_fractured + vabs : signal_speed(eos, str, rho, ep.P, in.v2) + visc.speed;
  A.P.V[i] = on ? V : in.V0;
  each<Sym<D>::K>([&](auto k) __attribute__((always_inline)) {
    A.P.s[k][i] = on ? (fractured ? 0.0 : sr.s[k]) : in.s[k];
  });
  A.P.p[i] = on ? (fractured ? 0.0 : ep.P) : in.P0;
  if constexpr (Strength::plastic) A.S.epsp[i] = on ? sr.st.epsp : in.st.epsp;
  if constexpr (HasE) A.S.e[i] = on ? ep.e : in.e0;
  if constexpr (HasQ) A.S.q[i] = on ? (fractured ? 0.0 : visc.q) : in.q0;
  if constexpr (HasWp) A.S.wp[i] += on ? sr.work * V / in.m : 0.0;
  return on ? sig : 0.0;
}

// Per point and step: the volume (debris, a point already expanded below rho_min, so fractured
// and stress-free, does not expand further: an isolated point keeps its APIC affine velocity,
// and its volume grew without bound, which read as solid in every volume sum (open porosity,
// the weld's volume fraction, uGIMP's domains); it still compresses, so it carries pressure
// again once packed back above rho_min), the strength part's deviator, the viscosity, the energy
// and pressure, then fracture: a point with tension below p_min (spall) or expanded below
// rho_min carries neither tension nor shear from now on (the elastic shear energy held in the
// deviator is released: energy.csv shows it), and no artificial viscosity either (a fractured
// point is debris, often alone in its cells, whose velocity gradient is noise; its viscous signal
// speed once stalled a porous run at dt = 7e-4 ns). Unselected points keep their state.
//
// The loop body is branch-free (both sides of every test computed, one selected, no division
// inside a conditional), everything in it inlined, the optional state a compile-time choice, and
// the loop `omp simd`: GCC 12 vectorizes it across particles (8 doubles per AVX-512 vector).
// What that needs, each found with -fopt-info-vec-missed: -fno-math-errno (CMakeLists.txt;
// otherwise every sqrt is a call that may set errno, "control flow in loop"); `simd` on the
// pragma (a max reduction over doubles is not vectorized without it, NaN semantics); the
// parameters and arrays copied into locals before the loop (a load under a condition through
// the params reference is an unsupported masked load); no aggregate in the loop body itself (see
// update_point), small aggregates passed to the steps and returned by value (a pointer to a
// local or an output reference keeps the loop scalar); bitwise
// | and & on the tests, not || and && (short-circuit masks did not convert). The vector body and
// the remainder do the same operations in the same order, each rounded as written
// (-ffp-contract=off), so a result does not depend on which one processes a particle, nor on
// where a block or a thread's share begins: bitwise the same for any thread count and block
// split (tests/test_contact.cpp and tests/test_elastic.cpp, "determinism").
//
// Points [first, last) on the calling thread; L.at(r, c)[i] is the gradient of point first + i.
template <bool Selective, bool HasE, bool HasQ, bool HasWp, bool Midstep, class Eos, class Strength>
ConstitutiveResult constitutive_range(const ParticleView& P, const ConstitutiveState& S, const Gradient& L,
                                      std::size_t first, std::size_t last, const ConstitutiveParams& q,
                                      const Eos& eos, const Strength& str, Selection sel) {
  const std::size_t cnt = last - first;
  double vmax = 0.0;
  std::ptrdiff_t bad = static_cast<std::ptrdiff_t>(cnt);
  // the parameters and parts as locals: a load through a reference that the compiler sinks
  // under a condition is a masked load it does not vectorize
  const ConstitutiveParams prm = q;
  const Eos eos_l = eos;
  const Strength str_l = str;
  // a fractured point's signal speed: the sound speed at rest (its stress is zero)
  const double c_fractured = std::sqrt(eos.bulk_modulus(eos.rho0, 0.0) / eos.rho0);
  const RangeArrays A{P, S, L, sel, first};
#pragma omp simd reduction(max : vmax) reduction(min : bad)
  for (std::size_t p = 0; p < cnt; ++p) {
    const bool on = !Selective || A.sel.select[A.sel.body[A.first + p]];
    const double V = step_volume(A, p, prm);
    bad = std::min(bad, on & !(V > 0.0) ? static_cast<std::ptrdiff_t>(p) : static_cast<std::ptrdiff_t>(cnt));
    vmax = std::max(vmax, update_point<HasE, HasQ, HasWp, Midstep>(A, p, on, V, prm, eos_l, str_l, c_fractured));
  }
  return {vmax, bad == static_cast<std::ptrdiff_t>(cnt) ? -1 : static_cast<std::ptrdiff_t>(first) + bad};
}

// The constitutive update of points [first, last) on the calling thread, L as above (a block
// buffer of kern::g2p_blocks, or arrays over all points offset to first): the optional state
// (energy, viscosity, plastic work, selection) chosen at run time, each combination its own loop.
// Only the combinations that can occur are compiled (each is a vectorized loop, and they were
// most of the engine's compile time): an EOS that needs energy always has it (S.e is required
// for it), and plastic work is tracked only by a plastic strength part (a strength part without
// plastic work would add zero to it).
template <class Eos, class Strength>
ConstitutiveResult constitutive_block(const ParticleView& P, const ConstitutiveState& S, const Gradient& L,
                                      std::size_t first, std::size_t last, const ConstitutiveParams& q,
                                      const Eos& eos, const Strength& str, Selection sel = {}) {
  const bool qv = S.q != nullptr, wp = S.wp != nullptr, selective = sel.select != nullptr;
  using T = std::true_type;
  using F = std::false_type;
  auto run = [&](auto Sel, auto E, auto Q) {
    constexpr bool s_ = decltype(Sel)::value, e_ = decltype(E)::value, q_ = decltype(Q)::value;
    // the mid-step energy update exists only with an energy field
    auto mid = [&](auto W) {
      constexpr bool w_ = decltype(W)::value;
      if constexpr (e_) {
        // q.midstep reads L.work(k): only kern::g2p_blocks' heating USL pass writes it
        if (q.midstep) return constitutive_range<s_, e_, q_, w_, true>(P, S, L, first, last, q, eos, str, sel);
      }
      return constitutive_range<s_, e_, q_, w_, false>(P, S, L, first, last, q, eos, str, sel);
    };
    if constexpr (Strength::plastic) {
      if (wp) return mid(T{});
    }
    return mid(F{});
  };
  auto by_state = [&](auto Sel) {
    if constexpr (!Eos::needs_energy) {
      if (S.e == nullptr) return qv ? run(Sel, F{}, T{}) : run(Sel, F{}, F{});
    }
    return qv ? run(Sel, T{}, T{}) : run(Sel, T{}, F{});
  };
  return selective ? by_state(T{}) : by_state(F{});
}

// The constitutive update of all n points, L in arrays over all of them, each thread its share
// (thread_share). The engine runs it inside the last gather pass instead (kern::g2p_blocks).
template <class Eos, class Strength>
ConstitutiveResult constitutive_update(const ParticleView& P, const ConstitutiveState& S, const Gradient& L,
                                       std::size_t n, const ConstitutiveParams& q, const Eos& eos,
                                       const Strength& str, Selection sel = {}) {
  ConstitutiveResult r;
#pragma omp parallel
  {
    const auto [b, e] = thread_share(n);
    const ConstitutiveResult own = constitutive_block(P, S, L + b, b, e, q, eos, str, sel);
#pragma omp critical(smpm_constitutive_merge)
    r.merge(own);
  }
  return r;
}

template <class Eos, class Strength>
double max_signal_speed(const ParticleView& P, std::size_t n, const Eos& eos, const Strength& str,
                        Selection sel = {}) {
  double vmax = 0.0;
#pragma omp parallel for schedule(static) reduction(max : vmax)
  for (std::size_t p = 0; p < n; ++p) {
    if (!sel(p)) continue;
    double v2 = P.v[0][p] * P.v[0][p];
    for (int d = 1; d < kDim; ++d) v2 += P.v[d][p] * P.v[d][p];
    vmax = std::max(vmax, signal_speed(eos, str, P.m[p] / P.V[p], P.p[p], v2));
  }
  return vmax;
}

}  // namespace SMPM_NS::kern
