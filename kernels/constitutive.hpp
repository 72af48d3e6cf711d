// Constitutive update over particle arrays. A material is an EOS part (pressure) and a
// strength part (deviatoric stress), passed as template arguments: one loop per pair, no
// virtual calls per particle. Per particle and step:
//   volume      V <- V det(I + dt L)
//   deviator    Jaumann trial step, then the strength part (elastic, radial return, none)
//   viscosity   q = rho l (c_Q l tr(D)^2 - c_L c tr(D)) in compression (optional)
//   energy      mid-step L: e <- e + dt V0 sigma_old : D / m, sigma_old = s - (P + q) I the
//               stress the scatter used: exactly the work of the internal forces over the
//               grid's mid-step velocity (kern::g2p_particle), so the step conserves energy;
//               updated L: e <- e + (deviatoric work - (P_mid + q) dV) / m, time-centred
//   pressure    P <- EOS(rho, e)
//   signal      c_L + |v| for the next CFL step
#pragma once
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "views.hpp"

namespace smpm::kern {

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

// Elastic trial step of the deviator: ds/dt = 2 G dev(D) + W s - s W (Jaumann), plane strain
// (D_zz = 0, s_zz = -(s_xx + s_yy)); w = W_xy = (L_xy - L_yx) / 2. Written out in scalars: with
// W = [0 w; -w 0], W s - s W = [2 w s_xy, w (s_yy - s_xx); same, -2 w s_xy], and the in-plane
// part of dev(D) subtracts tr(D) / 3 from each diagonal entry. (tests/test_material.cpp checks
// it against the 2x2 matrix expression in Eigen.) Scalars, not Eigen temporaries: inside the
// particle loop GCC 12 kept the Eigen 2x2 matrices as stack temporaries (docs/performance.md).
SMPM_INLINE void jaumann_trial(double G, double& sxx, double& syy, double& sxy, double dxx, double dyy, double dxy,
                               double w, double dt) {
  const double third_tr = (dxx + dyy) / 3.0, spin = w * (syy - sxx), g2 = 2.0 * G;
  const double nxx = sxx + dt * (g2 * (dxx - third_tr) + 2.0 * w * sxy);
  const double nyy = syy + dt * (g2 * (dyy - third_tr) - 2.0 * w * sxy);
  const double nxy = sxy + dt * (g2 * dxy + spin);
  sxx = nxx;
  syy = nyy;
  sxy = nxy;
}

// sqrt(3 J2) of a plane-strain deviator (s_zz = -(s_xx + s_yy)).
SMPM_INLINE double von_mises(double sxx, double syy, double sxy) {
  const double szz = -(sxx + syy);
  return std::sqrt(1.5 * (sxx * sxx + syy * syy + 2.0 * sxy * sxy + szz * szz));
}

// No shear strength: the deviator stays zero.
struct NoStrength {
  static constexpr bool plastic = false;
  double shear_modulus() const { return 0.0; }
  SMPM_INLINE double update(double& sxx, double& syy, double& sxy, double, double, double, double, double, double*) const {
    sxx = syy = sxy = 0.0;
    return 0.0;
  }
};

struct ElasticStrength {
  static constexpr bool plastic = false;
  double G = 0.0;
  double shear_modulus() const { return G; }
  SMPM_INLINE double update(double& sxx, double& syy, double& sxy, double dxx, double dyy, double dxy, double w, double dt,
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
  SMPM_INLINE double update(double& sxx, double& syy, double& sxy, double dxx, double dyy, double dxy, double w, double dt,
                double* epsp) const {
    jaumann_trial(G, sxx, syy, sxy, dxx, dyy, dxy, w, dt);
    const double q = von_mises(sxx, syy, sxy);
    const double Y = Y0 + H * *epsp;
    // branch-free: an elastic step has deps = 0 and f = 1; the divisions are computed for every
    // point (a division inside a conditional keeps GCC from if-converting the loop)
    const bool flows = q > Y;
    const double deps_flow = (q - Y) / (3.0 * G + H);
    const double deps = flows ? deps_flow : 0.0;
    const double Ynew = Y + H * deps;
    const double ratio = Ynew / (flows ? q : 1.0);
    const double f = flows ? ratio : 1.0;
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
  // L is the gather's mid-step one (kern::G2PParams::mid = 0.5): the energy takes the work of
  // the old stress, dt V0 sigma_old : D, which balances the grid's kinetic energy exactly; else
  // the time-centred update (see constitutive_range)
  bool midstep = false;
};

// Fastest signal speed of a particle: longitudinal wave speed plus |v|.
template <class Eos, class Strength>
SMPM_INLINE double signal_speed(const Eos& eos, const Strength& str, double rho, double P, double vx, double vy) {
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
  // the result of two sets of points together (max and min: the order of merging does not matter)
  void merge(const ConstitutiveResult& o) {
    max_speed = std::max(max_speed, o.max_speed);
    if (o.bad >= 0 && (bad < 0 || o.bad < bad)) bad = o.bad;
  }
};

// The loop body is branch-free (both sides of every test computed, one selected, no division
// inside a conditional), everything in it inlined, the optional state a compile-time choice, and
// the loop `omp simd`: GCC 12 vectorizes it across particles (8 doubles per AVX-512 vector).
// What that needs, each found with -fopt-info-vec-missed: -fno-math-errno (CMakeLists.txt;
// otherwise every sqrt is a call that may set errno, "control flow in loop"); `simd` on the
// pragma (a max reduction over doubles is not vectorized without it, NaN semantics); the
// parameters read into locals before the loop (a load under a condition through the params
// reference is an unsupported masked load); bitwise | and & on the tests, not || and &&
// (short-circuit masks did not convert). The vector body and the remainder do the same
// operations in the same order, each rounded as written (-ffp-contract=off), so a result does
// not depend on which one processes a particle, nor on where a block or a thread's share
// begins: bitwise the same for any thread count and block split (tests/test_contact.cpp and
// tests/test_elastic.cpp, "determinism").
//
// Points [first, last) on the calling thread; L.at(0, 0)[i] ... is the gradient of point first + i.
template <bool Selective, bool HasE, bool HasQ, bool HasWp, bool Midstep, class Eos, class Strength>
ConstitutiveResult constitutive_range(const ParticleView& P, const ConstitutiveState& S, const Gradient& L,
                                      std::size_t first, std::size_t last, const ConstitutiveParams& q,
                                      const Eos& eos, const Strength& str, Selection sel) {
  const std::size_t cnt = last - first;
  double vmax = 0.0;
  std::ptrdiff_t bad = static_cast<std::ptrdiff_t>(cnt);
  const double dt = q.dt, l = q.av_length, p_min = q.p_min, rho_min = q.rho_min;
  const double cQ = q.av_quadratic, cL = q.av_linear;
  // a fractured point's signal speed: the sound speed at rest (its stress is zero)
  const double c_fractured = std::sqrt(eos.bulk_modulus(eos.rho0, 0.0) / eos.rho0);
  // every array through a local restrict pointer to the range's first point: the view's
  // members might alias the stores, so the compiler would reload them for every point
  const double* __restrict Lxxp = L.at(0, 0);
  const double* __restrict Lxyp = L.at(0, 1);
  const double* __restrict Lyxp = L.at(1, 0);
  const double* __restrict Lyyp = L.at(1, 1);
  // the mid-step rate of the energy's work (Midstep; kern::g2p_blocks' heating pass writes it)
  const double* __restrict Wxxp = Midstep ? L.work(0) : nullptr;
  const double* __restrict Wyyp = Midstep ? L.work(1) : nullptr;
  const double* __restrict Wxyp = Midstep ? L.work(2) : nullptr;
  const double* __restrict mp = P.m + first;
  const double* __restrict vxp = P.vel(0) + first;
  const double* __restrict vyp = P.vel(1) + first;
  double* __restrict Vp = P.V + first;
  double* __restrict sxxp = P.dev(0) + first;
  double* __restrict syyp = P.dev(1) + first;
  double* __restrict sxyp = P.dev(2) + first;
  double* __restrict pp = P.p + first;
  double* __restrict ep = HasE ? S.e + first : nullptr;
  double* __restrict qp = HasQ ? S.q + first : nullptr;
  double* __restrict epspp = Strength::plastic ? S.epsp + first : nullptr;
  double* __restrict wpp = HasWp ? S.wp + first : nullptr;
  const std::uint8_t* __restrict bodyp = Selective ? sel.body + first : nullptr;
  const std::uint8_t* __restrict selectp = sel.select;
#pragma omp simd reduction(max : vmax) reduction(min : bad)
  for (std::size_t p = 0; p < cnt; ++p) {
    const bool on = !Selective || selectp[bodyp[p]];
    const double lxx = Lxxp[p], lxy = Lxyp[p], lyx = Lyxp[p], lyy = Lyyp[p];
    const double jinc = (1.0 + dt * lxx) * (1.0 + dt * lyy) - dt * dt * lxy * lyx;
    const double V0 = Vp[p], m = mp[p];
    // debris (a point already expanded below rho_min, so fractured, stress-free) does not expand
    // further: an isolated point keeps its APIC affine velocity, and its volume grew without
    // bound (rho 1e-4 kg/m^3 at the study's free top), which read as solid in every volume
    // sum (open porosity, the weld's volume fraction, uGIMP's domains). It still compresses,
    // so it carries pressure again once packed back above rho_min. No work either way: it has
    // no stress.
    const double V = V0 * ((m < rho_min * V0) ? std::min(jinc, 1.0) : jinc);
    bad = std::min(bad, on & !(V > 0.0) ? static_cast<std::ptrdiff_t>(p) : static_cast<std::ptrdiff_t>(cnt));
    const double rho = m / V;
    const double dxy = 0.5 * (lxy + lyx), w = 0.5 * (lxy - lyx), trD = lxx + lyy;
    const double a0 = sxxp[p], b0 = syyp[p], c0 = sxyp[p];
    double sxx = a0, syy = b0, sxy = c0;
    double epsp = 0.0;
    if constexpr (Strength::plastic) epsp = epspp[p];
    const double Wp = str.update(sxx, syy, sxy, lxx, lyy, dxy, w, dt, &epsp);
    const double P0 = pp[p];
    double qv = 0.0, qspeed = 0.0;
    if constexpr (HasQ) {
      const double c = std::sqrt(eos.bulk_modulus(rho, P0) / rho);
      const bool comp = trD < 0.0;
      qv = comp ? rho * l * (cQ * l * trD * trD - cL * c * trD) : 0.0;
      qspeed = comp ? 2.0 * cQ * l * -trD : 0.0;
    }
    double Pn, e = 0.0;
    const double dV = V - V0;
    if constexpr (HasE) {
      // the work of the stress the scatter used (deviator, pressure and viscous pressure at the
      // start of the step, volume V0) over the step's mid-step rate: dt V0 sigma : D_mid. It is
      // exactly minus the work of the internal forces on the grid, dt f_i . v_i with the
      // mid-step velocity the gather formed D_mid from (kern::g2p_particle): kinetic plus
      // internal energy is conserved by the step. The volume, the deviator and the viscosity
      // take the updated L (symplectic; with D_mid there too round-off grew without bound in
      // thin ligaments, docs/method.md). (The time-centred update this replaced, solved for P at
      // mid-step, made the Hugoniot second order in dt but left the energy of the step
      // unbalanced by O(dt^2) per node; at partly filled nodes of void faces that was a 4-10 %
      // loss over a porous run.) A point that fractures takes the work of the stress it had,
      // this same one.
      const double e_old = ep[p], cold = eos.cold(rho);
      if constexpr (Midstep) {
        const double q0 = HasQ ? qp[p] : 0.0;
        const double mxx = Wxxp[p], myy = Wyyp[p], mxy = Wxyp[p];
        const double sD = a0 * mxx + b0 * myy + 2.0 * c0 * mxy - (P0 + q0) * (mxx + myy);
        e = e_old + dt * V0 * sD / m;
      } else {
      // updated-velocity L (q.midstep false): deviatoric work with the time-centred stress and
      // mid-step volume, pressure work with P at mid-step, solved exactly (P is linear in e:
      // P = cold(rho) + Gamma rho e, Gamma rho constant); a point that fractures takes the
      // work of the stress it had, the centred mean of the old stress and zero (not the trial
      // deviator, which never acts: with it, expanding debris gained energy without bound)
      const double sDc = 0.5 * ((a0 + sxx) * lxx + (b0 + syy) * lyy + 2.0 * (c0 + sxy) * dxy);
      const double e_c = (e_old + (dt * 0.5 * (V0 + V) * sDc - (0.5 * (P0 + cold) + qv) * dV) / m) /
                         (1.0 + 0.5 * eos.gamma_rho() * dV / m);
      const double sD_fr = 0.5 * (a0 * lxx + b0 * lyy + 2.0 * c0 * dxy);
      const double e_fr = e_old + (dt * 0.5 * (V0 + V) * sD_fr - 0.5 * P0 * dV) / m;
      const bool fr = (cold + eos.gamma_rho() * e_c < p_min) | (rho < rho_min);
      e = fr ? e_fr : e_c;
      }
      Pn = cold + eos.gamma_rho() * e;
    } else {
      Pn = eos.pressure(rho, 0.0);
    }
    // Fractured (spall: tension below p_min, or expansion below rho_min): carries neither
    // tension nor shear from now on. The elastic shear energy held in the deviator is released
    // (lost): energy.csv shows it. No artificial viscosity either: a fractured point is debris,
    // often alone in its cells, whose velocity gradient is noise; a viscous signal speed from
    // it stalled a 2 us porous run at dt = 7e-4 ns when the compaction front reached the free
    // top and it spalled.
    const bool fractured = (Pn < p_min) | (rho < rho_min);
    const double vabs = std::sqrt(vxp[p] * vxp[p] + vyp[p] * vyp[p]);
    const double sig = fractured ? c_fractured + vabs : signal_speed(eos, str, rho, Pn, vxp[p], vyp[p]) + qspeed;
    vmax = std::max(vmax, on ? sig : 0.0);
    // stores: unselected points keep their state
    Vp[p] = on ? V : V0;
    sxxp[p] = on ? (fractured ? 0.0 : sxx) : a0;
    syyp[p] = on ? (fractured ? 0.0 : syy) : b0;
    sxyp[p] = on ? (fractured ? 0.0 : sxy) : c0;
    pp[p] = on ? (fractured ? 0.0 : Pn) : P0;
    if constexpr (Strength::plastic) epspp[p] = on ? epsp : epspp[p];
    if constexpr (HasE) ep[p] = on ? e : ep[p];
    if constexpr (HasQ) qp[p] = on ? (fractured ? 0.0 : qv) : qp[p];
    if constexpr (HasWp) wpp[p] += on ? Wp * V / m : 0.0;
  }
  return {vmax, bad == static_cast<std::ptrdiff_t>(cnt) ? -1 : static_cast<std::ptrdiff_t>(first) + bad};
}

// The constitutive update of points [first, last) on the calling thread, L as above (the
// particles' arrays at first, or a block buffer of kern::g2p_blocks): the optional state
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
        // q.midstep reads L.work(0), wyy, wxy: only kern::g2p_blocks' heating USL pass writes them
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

// The constitutive update of all n points, L in the particles' arrays, each thread its share
// (thread_share). The engine runs it inside the last gather pass instead (kern::g2p_blocks).
template <class Eos, class Strength>
ConstitutiveResult constitutive_update(const ParticleView& P, const ConstitutiveState& S, std::size_t n,
                                       const ConstitutiveParams& q, const Eos& eos, const Strength& str,
                                       Selection sel = {}) {
  ConstitutiveResult r;
#pragma omp parallel
  {
    const auto [b, e] = thread_share(n);
    const ConstitutiveResult own = constitutive_block(P, S, Gradient::of(P) + b, b, e, q, eos, str, sel);
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
    vmax = std::max(vmax, signal_speed(eos, str, P.m[p] / P.V[p], P.p[p], P.vel(0)[p], P.vel(1)[p]));
  }
  return vmax;
}

}  // namespace smpm::kern
