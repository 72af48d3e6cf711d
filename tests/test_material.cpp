// Unit tests of the study's aluminium (docs/model.md, "Equation of state", "Exact checks"):
// Mie-Grueneisen EOS, Hugoniot from the code's EOS, isentrope-referenced temperature, von Mises
// radial return, the constitutive update along a uniaxial-strain path, and the case reader's
// material tables.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <toml++/toml.h>

#include "engine/case_reader.hpp"
#include "engine/diagnostics.hpp"
#include "engine/material.hpp"
#include "engine/scene.hpp"
#include "engine/thermo.hpp"
#include "kernels/constitutive.hpp"

using namespace smpm;

namespace {

// The study's aluminium, with the values of cases/materials.toml.
Material aluminium() {
  Material m;
  m.name = "aluminium";
  m.eos = MieGruneisenModel{5350.0, 1.34, 2.0};
  m.strength = VonMisesModel{120e6, 384e6};
  m.rho0 = 2700.0;
  m.E = 69e9;
  m.nu = 0.33;
  m.cv = 880.0;
  m.conductivity = 237.0;
  m.T0 = 300.0;
  m.heat_fraction = 1.0;
  m.temperature = TemperatureKind::Isentrope;
  return m;
}

double rel(double a, double b) { return std::fabs(a - b) / std::fabs(b); }

// The models of a material (which must hold them).
const MieGruneisenModel& mg(const Material& m) { return std::get<MieGruneisenModel>(m.eos); }
const VonMisesModel& vmm(const Material& m) { return std::get<VonMisesModel>(m.strength); }

// The strength parts' plane-strain (D = 2) step on three deviator scalars, written back.
kern::StrainRate<2> rate(double dxx, double dyy, double dxy, double w) { return {{{dxx, dyy, dxy}}, {{w}}}; }
void jaumann_trial(double G, double& sxx, double& syy, double& sxy, double dxx, double dyy, double dxy, double w,
                   double dt) {
  const kern::Sym<2> n = jaumann_trial(G, kern::Sym<2>{{sxx, syy, sxy}}, rate(dxx, dyy, dxy, w), dt);
  sxx = n[0];
  syy = n[1];
  sxy = n[2];
}
double von_mises(double sxx, double syy, double sxy) { return von_mises(kern::Sym<2>{{sxx, syy, sxy}}); }
template <class Strength>
double update(const Strength& str, double& sxx, double& syy, double& sxy, double dxx, double dyy, double dxy, double w,
              double dt, double* epsp) {
  kern::StrengthState st;
  st.epsp = *epsp;
  const kern::StrengthResult<2> r = str.update(kern::Sym<2>{{sxx, syy, sxy}}, rate(dxx, dyy, dxy, w), dt, st);
  sxx = r.s[0];
  syy = r.s[1];
  sxy = r.s[2];
  *epsp = r.st.epsp;
  return r.work;
}

}  // namespace

// ---- 1. EOS ------------------------------------------------------------------------------------

TEST_CASE("Mie-Grueneisen EOS of aluminium: reference state and sound speed", "[material][eos]") {
  const Material al = aluminium();
  const auto eos = al.gruneisen().value();
  const double rho0 = al.rho0, c0 = mg(al).c0, C = rho0 * c0 * c0;
  CHECK(eos.C == Approx(C).epsilon(1e-15));
  CHECK(eos.D == Approx(C * (2 * 1.34 - 1)).epsilon(1e-15));
  CHECK(eos.S == Approx(C * 0.34 * (3 * 1.34 - 1)).epsilon(1e-15));
  CHECK(eos.gamma_rho() == Approx(2.0 * 2700.0).epsilon(1e-15));

  // P(rho0, 0) = 0 exactly
  CHECK(eos.pressure(rho0, 0.0) == 0.0);
  CHECK(eos.cold(rho0) == 0.0);

  // dP/drho at (rho0, e = 0) = c0^2: analytic derivative and a central difference of pressure()
  CHECK(rel(eos.dcold_drho(rho0), c0 * c0) < 1e-9);
  const double h = 1e-7 * rho0;  // truncation across the kink of P'' at mu = 0: ~0.34 dmu = 3e-8
  const double fd = (eos.pressure(rho0 + h, 0.0) - eos.pressure(rho0 - h, 0.0)) / (2 * h);
  CHECK(rel(fd, c0 * c0) < 1e-6);
  // isentropic bulk modulus at the reference state: rho0 c0^2
  CHECK(rel(eos.bulk_modulus(rho0, 0.0), C) < 1e-12);
  CHECK(rel(al.bulk_modulus(), C) < 1e-15);
}

TEST_CASE("Mie-Grueneisen EOS: P and dcold/drho are continuous at mu = 0", "[material][eos]") {
  const auto eos = aluminium().gruneisen().value();
  const double rho0 = eos.rho0, c2 = eos.C / rho0;
  for (double dmu : {1e-6, 1e-9, 1e-12}) {
    const double rp = rho0 * (1 + dmu), rm = rho0 * (1 - dmu);
    const double e = 1234.5;
    // both sides of P tend to P(rho0, e) = gamma0 rho0 e, with slope c0^2 on each side
    const double P0 = eos.gamma_rho() * e;
    CHECK(std::fabs(eos.pressure(rp, e) - P0) <= 1.01 * eos.C * dmu);
    CHECK(std::fabs(eos.pressure(rm, e) - P0) <= 1.01 * eos.C * dmu);
    CHECK(eos.cold(rp) > 0.0);
    CHECK(eos.cold(rm) < 0.0);
    CHECK(rel(eos.cold(rp) / (eos.C * (rp / rho0 - 1)), 1.0) < 1e-5);
    CHECK(rel(eos.cold(rm) / (eos.C * (rm / rho0 - 1)), 1.0) < 1e-12);
    // derivative from both sides -> c0^2
    CHECK(rel(eos.dcold_drho(rp), c2) < 1e-5);
    CHECK(rel(eos.dcold_drho(rm), c2) < 1e-12);
    CHECK(rel(eos.dcold_drho(rp), eos.dcold_drho(rm)) < 4 * dmu);
  }
}

TEST_CASE("Mie-Grueneisen EOS: the formulas of docs/model.md", "[material][eos]") {
  const Material al = aluminium();
  const auto eos = al.gruneisen().value();
  const double rho0 = al.rho0, C = rho0 * mg(al).c0 * mg(al).c0, lam = mg(al).s, g0 = mg(al).gamma0;
  const double D = C * (2 * lam - 1), S = C * (lam - 1) * (3 * lam - 1);
  // tension branch: P = C mu + gamma0 rho0 e
  for (double r : {0.99, 0.9, 0.7}) {
    for (double e : {0.0, 1e5, 2e6}) {
      const double rho = r * rho0, mu = r - 1;
      CHECK(rel(eos.pressure(rho, e), C * mu + g0 * rho0 * e) < 1e-12);
    }
  }
  // compression branch, written as in docs/model.md ("Equation of state") with gamma = gamma0 rho0 / rho
  for (double r : {1.01, 1.2, 1.5}) {
    for (double e : {0.0, 1e5, 2e6}) {
      const double rho = r * rho0, mu = r - 1, gamma = g0 * rho0 / rho;
      const double P = (C * mu + D * mu * mu + S * mu * mu * mu) * (1 - gamma * mu / 2) + gamma * rho * e;
      CHECK(rel(eos.pressure(rho, e), P) < 1e-12);
    }
  }
  // dcold_drho against a central difference of pressure() away from mu = 0, both branches
  for (double r : {0.8, 0.95, 1.05, 1.3, 1.6}) {
    const double rho = r * rho0, h = 1e-6 * rho0;
    const double fd = (eos.pressure(rho + h, 5e4) - eos.pressure(rho - h, 5e4)) / (2 * h);
    CHECK(rel(eos.dcold_drho(rho), fd) < 1e-6);
  }
}

// ---- 2. Hugoniot -------------------------------------------------------------------------------

TEST_CASE("Hugoniot of aluminium from the code's EOS against the table of docs/model.md", "[material][hugoniot]") {
  const Material al = aluminium();
  const auto eos = al.gruneisen().value();
  const double rho0 = al.rho0, c0 = mg(al).c0, lam = mg(al).s;
  struct Row {
    double up, Us, P, rho, T, T_simple;  // the table of docs/model.md, "Exact checks"
    double tol_lin;  // deviation of the EOS Hugoniot from the linear Us-up line (docs/model.md)
    double round_Us, round_P, round_rho;  // half a unit in the last digit of the table
  };
  // docs/model.md ("Exact checks"): the EOS reproduces the linear U_s-u_p Hugoniot to 0.1 % up to
  // 1 km/s, 0.4 % at 2 km/s. 0.2 % is asserted up to 1 km/s (0.09 % measured at 1 km/s); at
  // 2 km/s the EOS Hugoniot lies 0.43 % below the linear Us-up line (a property of the cubic EOS
  // form, not of the solver), so the documented 0.4 % is taken as 0.5 %, and the table comparison
  // adds the table's own rounding.
  const Row rows[] = {
      {500, 6020, 8.13e9, 2945, 366, 442, 2e-3, 0, 0, 0},
      {800, 6422, 13.87e9, 3084, 430, 664, 2e-3, 0, 0, 0},
      {1000, 6690, 18.06e9, 3175, 490, 868, 2e-3, 0, 0, 0},
      {2000, 8030, 43.4e9, 3596, 1111, 2573, 5e-3, 5.0 / 8030, 0.05 / 43.4, 0.5 / 3596},
  };
  for (const Row& r : rows) {
    INFO("up = " << r.up << " m/s");
    const HugoniotState h = hugoniot(al, r.up);
    INFO("code: Us = " << h.Us << ", P = " << h.P << ", rho = " << h.rho << ", e = " << h.e << ", T = " << h.T
                       << ", T_simple = " << h.T_simple);
    // Rankine-Hugoniot identities of the returned state
    CHECK(rel(h.up, r.up) < 1e-9);
    CHECK(rel(h.e, 0.5 * r.up * r.up) < 1e-9);
    CHECK(rel(h.P, rho0 * h.Us * r.up) < 1e-9);
    CHECK(rel(h.rho, rho0 * h.Us / (h.Us - r.up)) < 1e-9);
    // the Hugoniot point lies on the EOS
    CHECK(rel(eos.pressure(h.rho, h.e), h.P) < 1e-9);
    // against the linear Us-up Hugoniot: Us = c0 + s up, P = rho0 Us up, rho = rho0 Us / (Us - up)
    const double Us = c0 + lam * r.up, P = rho0 * Us * r.up, rho = rho0 * Us / (Us - r.up);
    CHECK(rel(h.Us, Us) < r.tol_lin);
    CHECK(rel(h.P, P) < r.tol_lin);
    CHECK(rel(h.rho, rho) < r.tol_lin);
    // against the table's (rounded) values
    CHECK(rel(h.Us, r.Us) < r.tol_lin + r.round_Us);
    CHECK(rel(h.P, r.P) < r.tol_lin + r.round_P);
    CHECK(rel(h.rho, r.rho) < r.tol_lin + r.round_rho);
    // temperatures
    CHECK(rel(h.T, r.T) < 0.01);
    CHECK(rel(h.T_simple, r.T_simple) < 0.01);
    CHECK(rel(h.T_simple, al.T0 + h.e / al.cv) < 1e-12);
    CHECK(h.T < h.T_simple);  // cold compression energy is not heat
  }
  // the linear-Hugoniot claim of docs/model.md for up to 1 km/s: 0.1 %
  CHECK(rel(hugoniot(al, 1000).Us, c0 + lam * 1000) < 1e-3);
  // beyond the range: said, not capped (the old 1.999 rho0 bracket gave up 7274 m/s for any
  // larger input); within it, the speed asked for
  CHECK(hugoniot(al, 1000).in_range);
  const HugoniotState fast = hugoniot(al, 9000);
  CHECK(fast.in_range);
  CHECK(rel(fast.up, 9000) < 1e-6);
  const HugoniotState absurd = hugoniot(al, 1e9);
  CHECK_FALSE(absurd.in_range);
  CHECK(absurd.up < 1e6);
}

// ---- 3. Thermo ---------------------------------------------------------------------------------

namespace {
// Independent RK4 of de/deta = P(rho(eta), e) V0, eta = 1 - rho0/rho, from (eta 0, e 0).
double isentrope_energy_rk4(const kern::MieGruneisenEos& eos, double rho, int n = 20000) {
  const double V0 = 1.0 / eos.rho0, eta1 = 1.0 - eos.rho0 / rho, h = eta1 / n;
  auto f = [&](double eta, double e) { return eos.pressure(eos.rho0 / (1.0 - eta), e) * V0; };
  double e = 0.0;
  for (int i = 0; i < n; ++i) {
    const double eta = i * h;
    const double k1 = f(eta, e), k2 = f(eta + h / 2, e + h / 2 * k1), k3 = f(eta + h / 2, e + h / 2 * k2),
                 k4 = f(eta + h, e + h * k3);
    e += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
  }
  return e;
}
}  // namespace

TEST_CASE("Thermo: the isentrope through (rho0, T0)", "[material][thermo]") {
  const Material al = aluminium();
  const auto eos = al.gruneisen().value();
  const Thermo th(al);
  const double rho0 = al.rho0;
  // e_s(rho0) = 0 up to the linear interpolation of the table (eta = 0 is not a table node):
  // c0^2 d^2 / 8 = 0.16 J/kg with d = 1.75 / 8191; asserted below 1 mK of heat (cv * 1e-3 J/kg).
  CHECK(std::fabs(th.isentrope_energy(rho0)) < al.cv * 1e-3);
  CHECK(th.isentrope_temperature(rho0) == al.T0);
  CHECK(std::fabs(th.temperature(rho0, 0.0) - al.T0) < 1e-3);
  // T_s(V) = T0 exp(gamma0 (V0 - V) / V0)
  for (double r : {0.9, 1.2, 1.4}) {
    const double V0 = 1 / rho0, V = 1 / (r * rho0);
    CHECK(rel(th.isentrope_temperature(r * rho0), al.T0 * std::exp(mg(al).gamma0 * (V0 - V) / V0)) < 1e-14);
  }

  // de_s/dV = -P(V, e_s(V)), five-point central difference with dV = 5e-3 V: truncation ~1e-8; the
  // linear interpolation of the table contributes at most 1.5 (d^2/8) e'' / (dV/V0) ~ 4e-5 at 1.05.
  for (double r : {1.05, 1.2, 1.4, 0.9}) {
    INFO("rho/rho0 = " << r);
    const double rho = r * rho0, V = 1 / rho, h = 5e-3 * V;
    auto es = [&](double k) { return th.isentrope_energy(1.0 / (V + k * h)); };
    const double dedV = (es(-2) - 8 * es(-1) + 8 * es(1) - es(2)) / (12 * h);
    const double P = eos.pressure(rho, th.isentrope_energy(rho));
    CHECK(rel(dedV, -P) < 1e-4);
    // on the isentrope the temperature is T_s
    CHECK(rel(th.temperature(rho, th.isentrope_energy(rho)), th.isentrope_temperature(rho)) < 1e-14);
    // the table against an independent integration; interpolation error (d^2/8) e''/e <= 6e-6
    CHECK(rel(th.isentrope_energy(rho), isentrope_energy_rk4(eos, rho)) < 1e-5);
    // compression and tension both store energy on the isentrope
    CHECK(th.isentrope_energy(rho) > 0.0);
  }
  // temperature is linear in e with slope 1/cv
  CHECK(rel(th.temperature(1.2 * rho0, 5e5) - th.temperature(1.2 * rho0, 0.0), 5e5 / al.cv) < 1e-12);
  // the simple model: T0 + e / cv
  Material simple = al;
  simple.temperature = TemperatureKind::Simple;
  CHECK(rel(Thermo(simple).temperature(1.2 * rho0, 5e5), al.T0 + 5e5 / al.cv) < 1e-14);
}

// ---- 4. Radial return --------------------------------------------------------------------------

TEST_CASE("VonMisesStrength: radial return onto the hardened surface", "[material][plasticity]") {
  const Material al = aluminium();
  const double G = al.shear_modulus(), Y0 = vmm(al).Y0, H = vmm(al).H;
  CHECK(rel(G, 69e9 / 2.66) < 1e-15);
  const kern::VonMisesStrength vm{G, Y0, H};

  // a pre-hardened state with a deviator inside the surface, then a large strain increment
  const double epsp0 = 0.02;
  const double s0[3] = {30e6, -50e6, 20e6};
  const double dxx = -1e-2, dyy = 1.5e-2, dxy = 5e-3, w = 1.5e-3, dt = 1.0;
  REQUIRE(von_mises(s0[0], s0[1], s0[2]) < Y0 + H * epsp0);
  double t[3] = {s0[0], s0[1], s0[2]};
  jaumann_trial(G, t[0], t[1], t[2], dxx, dyy, dxy, w, dt);
  const double q_trial = von_mises(t[0], t[1], t[2]);
  const double Y = Y0 + H * epsp0;
  REQUIRE(q_trial > 5 * Y);  // well beyond yield

  double s[3] = {s0[0], s0[1], s0[2]};
  double epsp = epsp0;
  const double Wp = update(vm, s[0], s[1], s[2], dxx, dyy, dxy, w, dt, &epsp);
  const double deps = epsp - epsp0;
  // consistency: on the hardened surface after the step
  CHECK(rel(von_mises(s[0], s[1], s[2]), Y0 + H * epsp) < 1e-10);
  // plastic strain increment
  CHECK(rel(deps, (q_trial - Y) / (3 * G + H)) < 1e-12);
  // radial: the final deviator is the trial one scaled by Y_new / q_trial
  const double Ynew = Y0 + H * epsp, f = Ynew / q_trial;
  for (int i = 0; i < 3; ++i) CHECK(rel(s[i], f * t[i]) < 1e-12);
  CHECK(std::fabs(s[0] * t[1] - s[1] * t[0]) < 1e-12 * std::fabs(s[0] * t[1]));
  CHECK(std::fabs(s[2] * t[1] - s[1] * t[2]) < 1e-12 * std::fabs(s[2] * t[1]));
  // plastic work per unit volume
  CHECK(rel(Wp, Ynew * deps) < 1e-12);
  CHECK(Wp > 0.0);

  // from the virgin state too (eps_p = 0)
  {
    double a = 0, b = 0, c = 0, ep = 0;
    const double W = update(vm, a, b, c, 0.0, -1e-2, 0.0, 0.0, 1.0, &ep);
    const double qt = 1.5 * (4.0 / 3.0) * G * 1e-2;  // uniaxial strain: q = 2 G |eps|
    CHECK(rel(ep, (qt - Y0) / (3 * G + H)) < 1e-12);
    CHECK(rel(von_mises(a, b, c), Y0 + H * ep) < 1e-10);
    CHECK(rel(W, (Y0 + H * ep) * ep) < 1e-12);
  }
}

TEST_CASE("VonMisesStrength: an elastic step changes only the deviator", "[material][plasticity]") {
  const Material al = aluminium();
  const double G = al.shear_modulus();
  const kern::VonMisesStrength vm{G, vmm(al).Y0, vmm(al).H};
  const double epsp0 = 0.01;
  const double dxx = 1e-4, dyy = -2e-4, dxy = 5e-5, w = 3e-4, dt = 1.0;
  double t[3] = {10e6, -20e6, 5e6};
  double s[3] = {t[0], t[1], t[2]};
  jaumann_trial(G, t[0], t[1], t[2], dxx, dyy, dxy, w, dt);
  REQUIRE(von_mises(t[0], t[1], t[2]) < vmm(al).Y0 + vmm(al).H * epsp0);
  double epsp = epsp0;
  const double Wp = update(vm, s[0], s[1], s[2], dxx, dyy, dxy, w, dt, &epsp);
  CHECK(Wp == 0.0);
  CHECK(epsp == epsp0);
  for (int i = 0; i < 3; ++i) CHECK(s[i] == t[i]);
  // the trial step: 2 G dev(D) dt plus the Jaumann rotation terms
  CHECK(rel(t[0], 10e6 + 2 * G * (dxx - (dxx + dyy) / 3) + 2 * w * 5e6) < 1e-14);
  CHECK(rel(t[1], -20e6 + 2 * G * (dyy - (dxx + dyy) / 3) - 2 * w * 5e6) < 1e-14);
  CHECK(rel(t[2], 5e6 + 2 * G * dxy + w * (-20e6 - 10e6)) < 1e-14);
}

// Bingham flow in pure shear, D = diag(d, -d) at a constant d: the equivalent rate
// r = sqrt(2/3 D:D) = 2 d / sqrt(3) and, with H = 0, dq/dt = 3 G (r - d(eps_p)/dt) where
// q = Y0 + 3 eta d(eps_p)/dt. Exact: q = 3 G r t up to the yield time t_y = Y0 / (3 G r), then
// q = Y0 + 3 eta r (1 - exp(-(t - t_y) / tau)), tau = eta / G. Backward Euler reaches the steady
// flow stress Y0 + 3 eta r at any dt and the transient to first order in dt.
TEST_CASE("VonMisesStrength with a flow viscosity: Bingham relaxation in pure shear", "[material][plasticity]") {
  const Material al = aluminium();
  const double G = al.shear_modulus(), Y0 = vmm(al).Y0, eta = 1e4, tau = eta / G;
  const double r = Y0 / (12.0 * eta), d = r * std::sqrt(3.0) / 2.0;  // t_y = 4 tau, 3 eta r = Y0 / 4
  const double ty = Y0 / (3.0 * G * r), over = 3.0 * eta * r;
  const kern::VonMisesStrength vm{G, Y0, 0.0, eta};
  // q [Pa] at t_y + tau and t_y + 20 tau, the plastic work [J/m^3] and strain, at steps tau / k
  struct Run {
    double q1, q20, work, epsp;
  };
  const auto run = [&](int k) {
    const double dt = tau / k;
    const long n1 = std::lround((ty + tau) / dt), n20 = std::lround((ty + 20.0 * tau) / dt);
    double sxx = 0, syy = 0, sxy = 0, epsp = 0;
    Run out{0, 0, 0, 0};
    for (long i = 1; i <= n20; ++i) {
      out.work += update(vm, sxx, syy, sxy, d, -d, 0.0, 0.0, dt, &epsp);
      if (i == n1) out.q1 = von_mises(sxx, syy, sxy);
    }
    out.q20 = von_mises(sxx, syy, sxy);
    out.epsp = epsp;
    return out;
  };
  const Run a = run(20), b = run(40);
  // the steady flow stress (relaxed to exp(-20)): 3 eta r above Y0, at any step
  CHECK(rel(a.q20 - Y0, over * (1.0 - std::exp(-20.0))) < 1e-7);
  CHECK(rel(b.q20 - Y0, over * (1.0 - std::exp(-20.0))) < 1e-7);
  // the transient: backward Euler, first order in dt (errors 0.9 and 0.46 % of 3 eta r)
  const double q1 = Y0 + over * (1.0 - std::exp(-1.0));
  const double ea = std::fabs(a.q1 - q1) / over, eb = std::fabs(b.q1 - q1) / over;
  CHECK(ea < 0.01);
  CHECK(ea / eb > 1.9);
  CHECK(ea / eb < 2.1);
  // the work is all dissipated at the flow stress, W = int q d(eps_p): between Y0 and the steady
  // flow stress times the plastic strain
  CHECK(b.work > Y0 * b.epsp);
  CHECK(b.work < (Y0 + over) * b.epsp);
  // eta = 0 is the rate-independent law, bitwise
  {
    const kern::VonMisesStrength v0{G, Y0, 384e6, 0.0}, v1{G, Y0, 384e6};
    double s0[3] = {0, 0, 0}, s1[3] = {0, 0, 0}, e0 = 0, e1 = 0;
    for (int i = 0; i < 50; ++i) {
      const double w0 = update(v0, s0[0], s0[1], s0[2], d, -d, 0.3 * d, 0.1 * d, ty / 4, &e0);
      const double w1 = update(v1, s1[0], s1[1], s1[2], d, -d, 0.3 * d, 0.1 * d, ty / 4, &e1);
      CHECK(w0 == w1);
    }
    for (int i = 0; i < 3; ++i) CHECK(s0[i] == s1[i]);
    CHECK(e0 == e1);
    CHECK(e0 > 0.0);
  }
}

// ---- 5. Uniaxial strain through the constitutive update -----------------------------------------

TEST_CASE("Constitutive update of aluminium along a uniaxial-strain compression", "[material][constitutive]") {
  const Material al = aluminium();
  const auto eos = al.gruneisen().value();
  const double G = al.shear_modulus(), Y0 = vmm(al).Y0, H = vmm(al).H, K = al.rho0 * mg(al).c0 * mg(al).c0;
  const kern::VonMisesStrength vm{G, Y0, H};

  // one particle, L_yy = -1e5 /s, dt = 1e-12 s: strain steps of 1e-7, to 6 times the yield strain
  const double V0 = 1e-10;
  double x = 0, y = 0, vx = 0, vy = 0, m = al.rho0 * V0, V = V0, sxx = 0, syy = 0, sxy = 0, p = 0;
  double Lxx = 0, Lxy = 0, Lyx = 0, Lyy = -1e5;
  double e = 0, epsp = 0, wp = 0;
  const kern::ParticleView P{&x,   &y,   &vx,     &vy,     &m,      &V,      &sxx,
                             &syy, &sxy, &p,      nullptr, nullptr, nullptr, nullptr, nullptr, nullptr};
  kern::Gradient Lg;
  Lg.L[0] = &Lxx, Lg.L[1] = &Lxy, Lg.L[2] = &Lyx, Lg.L[3] = &Lyy;
  const kern::ConstitutiveState S{&e, &epsp, nullptr, &wp};
  kern::ConstitutiveParams q;
  q.dt = 1e-12;

  const double epsY = Y0 / (2 * G);  // |eps| at first yield
  std::vector<double> Vs{V}, sig{syy - p};
  double err_el = 0, err_pl = 0, err_ep = 0, err_lat = 0;
  int n_el = 0, n_pl = 0, n_el_flow = 0, n_bad = 0;
  bool yielded = false;
  double sig_yield = 0, eps_yield = 0, P_yield = 0;
  while (std::log(V / V0) > -6 * epsY) {
    const double sig_prev = syy - p, eps_prev = std::log(V / V0), P_prev = p;
    const auto res = kern::constitutive_update(P, S, Lg, 1, q, eos, vm);
    if (res.bad != -1) ++n_bad;
    Vs.push_back(V);
    sig.push_back(syy - p);
    const double eps = std::log(V / V0);  // log strain: the hypoelastic rate integrates D
    if (!yielded && epsp > 0) {
      yielded = true;  // the last elastic state is the first-yield state (to one 1e-7 step)
      sig_yield = sig_prev;
      eps_yield = eps_prev;
      P_yield = P_prev;
    }
    err_lat = std::max(err_lat, rel(sxx, -0.5 * syy));
    if (std::fabs(eps) < 0.999 * epsY) {
      err_el = std::max(err_el, rel(syy, 4.0 / 3.0 * G * eps));
      if (epsp != 0.0) ++n_el_flow;
      ++n_el;
    } else if (std::fabs(eps) > 1.001 * epsY) {
      const double ep = (2 * G * std::fabs(eps) - Y0) / (3 * G + H);
      // against the strain scale |eps|: just past yield eps_p itself is tiny
      err_ep = std::max(err_ep, std::fabs(epsp - ep) / std::fabs(eps));
      err_pl = std::max(err_pl, rel(syy, -2.0 / 3.0 * (Y0 + H * ep)));
      ++n_pl;
    }
  }
  INFO("elastic steps " << n_el << ", plastic steps " << n_pl);
  CHECK(n_bad == 0);
  REQUIRE(n_el > 10000);
  REQUIRE(n_pl > 10000);
  // (a) deviatoric stress: closed form, elastic and plastic
  CHECK(err_el < 1e-6);
  CHECK(n_el_flow == 0);  // no plastic flow below the yield strain
  CHECK(err_pl < 1e-6);
  CHECK(err_ep < 1e-6);
  CHECK(err_lat < 1e-12);  // s_xx = s_zz = -s_yy / 2
  CHECK(sxy == 0.0);
  // a few explicit points: the end state
  {
    const double eps = std::log(V / V0);
    const double ep = (2 * G * std::fabs(eps) - Y0) / (3 * G + H);
    CHECK(rel(syy, -2.0 / 3.0 * (Y0 + H * ep)) < 1e-6);
    CHECK(rel(epsp, ep) < 1e-6);
    CHECK(rel(p, eos.pressure(al.rho0 * V0 / V, e)) < 1e-12);
  }
  // (b) the total stress at first yield is -HEL, HEL = Y0 (K / (2 G) + 2/3) = 259 MPa
  REQUIRE(yielded);
  const double HEL = Y0 * (K / (2 * G) + 2.0 / 3.0);
  CHECK(rel(HEL, 258.8e6) < 1e-3);
  CHECK(rel(std::fabs(eps_yield), epsY) < 1e-3);
  CHECK(rel(sig_yield, -HEL) < 0.01);
  CHECK(rel(P_yield, K * epsY) < 0.01);
  // (c) energy: the work done on the particle, sigma : D V dt = sigma_yy dV (tension-positive sigma,
  // so with sigma = -P I this is the familiar -P dV), e = int sigma_yy dV / m over the recorded path
  // (trapezoid); both sigma_yy and dV are negative in compression.
  double W = 0;
  for (std::size_t i = 1; i < Vs.size(); ++i) W += 0.5 * (sig[i - 1] + sig[i]) * (Vs[i] - Vs[i - 1]);
  CHECK(W > 0.0);
  CHECK(e > 0.0);
  CHECK(rel(e, W / m) < 1e-4);
  // the plastic work (tracked separately) is part of that work, not added on top of it
  CHECK(wp > 0.0);
  CHECK(wp < e);
}

// ---- 6. Case reading ---------------------------------------------------------------------------

namespace {

// A temporary directory with its own materials library; removed at the end of the test.
struct TempCaseDir {
  std::filesystem::path dir;
  TempCaseDir() {
    std::random_device rd;
    dir = std::filesystem::temp_directory_path() / ("smpm_test_material_" + std::to_string(rd()) + std::to_string(rd()));
    std::filesystem::create_directories(dir);
    std::ofstream(dir / "materials.toml") << R"(
[aluminium]
eos = "mie_gruneisen"
strength = "von_mises"
density_kg_m3 = 2700.0
youngs_modulus_GPa = 69.0
poisson_ratio = 0.33
yield_stress_MPa = 120.0
hardening_modulus_MPa = 384.0
bulk_sound_speed_m_s = 5350.0
hugoniot_slope = 1.34
gruneisen_gamma = 2.0
specific_heat_J_kgK = 880.0
thermal_conductivity_W_mK = 237.0
initial_temperature_K = 300.0
heat_fraction = 1.0
temperature = "isentrope"

[copper]
eos = "linear"
strength = "elastic"
density_kg_m3 = 8930.0
youngs_modulus_GPa = 128.0
poisson_ratio = 0.34
)";
  }
  ~TempCaseDir() {
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
  }
};

// A minimal valid case: a 20 x 20 um grid of 5 um cells, one body of material "al" whose table is
// `material` (TOML lines).
toml::table minimal_case(const std::string& material) {
  return toml::parse(R"(
[run]
end_time_ns = 1.0

[grid]
cell_size_um = 5.0
x_range_um = [0.0, 20.0]
y_range_um = [0.0, 20.0]

[materials.al]
)" + material + R"(

[[bodies]]
name = "block"
material = "al"
x_range_um = [0.0, 20.0]
y_range_um = [0.0, 10.0]
)");
}

// The CaseError message of building the case, or "" when it builds.
std::string case_error(const toml::table& doc, const std::filesystem::path& dir) {
  try {
    build_scene(doc, "test", dir);
  } catch (const CaseError& e) {
    return e.what();
  }
  return "";
}

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

void check_aluminium(const Material& m, double Y0) {
  const Material ref = aluminium();
  CHECK(model_name(m.eos) == "mie_gruneisen");
  CHECK(model_name(m.strength) == "von_mises");
  CHECK(m.temperature == TemperatureKind::Isentrope);
  CHECK(rel(m.rho0, ref.rho0) < 1e-15);
  CHECK(rel(m.E, ref.E) < 1e-15);
  CHECK(rel(m.nu, ref.nu) < 1e-15);
  CHECK(rel(vmm(m).Y0, Y0) < 1e-15);
  CHECK(rel(vmm(m).H, vmm(ref).H) < 1e-15);
  CHECK(rel(mg(m).c0, mg(ref).c0) < 1e-15);
  CHECK(rel(mg(m).s, mg(ref).s) < 1e-15);
  CHECK(rel(mg(m).gamma0, mg(ref).gamma0) < 1e-15);
  CHECK(rel(m.cv, ref.cv) < 1e-15);
  CHECK(rel(m.conductivity, ref.conductivity) < 1e-15);
  CHECK(rel(m.T0, ref.T0) < 1e-15);
  CHECK(m.heat_fraction == 1.0);
}

}  // namespace

TEST_CASE("Case reader: the library's aluminium has the study's values", "[material][case]") {
  const std::filesystem::path cases = std::filesystem::path(SHOCKMPM_SOURCE_DIR) / "cases";
  const Scene sc = build_scene(minimal_case(R"(base = "aluminium")"), "test", cases);
  REQUIRE(sc.materials.size() == 1);
  CHECK(sc.materials[0].name == "al");
  check_aluminium(sc.materials[0], 120e6);
  CHECK(rel(sc.materials[0].shear_modulus(), 25.94e9) < 1e-3);  // docs/model.md: G = 25.9 GPa
  // the same material written out in full in the case, without a base
  TempCaseDir tmp;
  const Scene inl = build_scene(minimal_case(R"(
eos = "mie_gruneisen"
strength = "von_mises"
density_kg_m3 = 2700.0
youngs_modulus_GPa = 69.0
poisson_ratio = 0.33
yield_stress_MPa = 120.0
hardening_modulus_MPa = 384.0
bulk_sound_speed_m_s = 5350.0
hugoniot_slope = 1.34
gruneisen_gamma = 2.0
specific_heat_J_kgK = 880.0
thermal_conductivity_W_mK = 237.0
initial_temperature_K = 300.0
)"),
                                "test", tmp.dir);
  check_aluminium(inl.materials[0], 120e6);
}

TEST_CASE("Case reader: material errors name the key, value and allowed range", "[material][case]") {
  TempCaseDir tmp;
  SECTION("unknown key on top of a base") {
    const std::string msg = case_error(minimal_case("base = \"aluminium\"\ncolour = \"silver\""), tmp.dir);
    INFO(msg);
    CHECK(contains(msg, "colour"));
    CHECK(contains(msg, "materials.al"));
  }
  SECTION("unknown key in a material written in full") {
    const std::string msg = case_error(
        minimal_case("density_kg_m3 = 2700.0\nyoungs_modulus_GPa = 69.0\npoisson_ratio = 0.33\nyield_strength_MPa = 1.0"),
        tmp.dir);
    INFO(msg);
    CHECK(contains(msg, "yield_strength_MPa"));
    CHECK(contains(msg, "materials.al"));
  }
  SECTION("negative yield stress") {
    const std::string msg = case_error(minimal_case("base = \"aluminium\"\nyield_stress_MPa = -5.0"), tmp.dir);
    INFO(msg);
    CHECK(contains(msg, "yield_stress_MPa"));
    CHECK(contains(msg, "-5"));
    CHECK(contains(msg, "out of range"));
    // allowed 0 to 1e15 Pa, stated in the key's unit: 0 to 1e9 MPa
    CHECK(contains(msg, "allowed 0 to "));
    CHECK((contains(msg, "1000000000") || contains(msg, "1e+09")));
  }
  SECTION("a base that is not in the library lists the library's names") {
    const std::string msg = case_error(minimal_case("base = \"nosuch\""), tmp.dir);
    INFO(msg);
    CHECK(contains(msg, "nosuch"));
    CHECK(contains(msg, "'aluminium'"));
    CHECK(contains(msg, "'copper'"));
    CHECK(contains(msg, "base"));
  }
  SECTION("a base without a library") {
    // a directory with no materials.toml at or above it cannot be guaranteed; name a missing file
    toml::table doc = minimal_case("base = \"aluminium\"");
    doc.insert_or_assign("materials_file", "no_such_library.toml");
    const std::string msg = case_error(doc, tmp.dir);
    INFO(msg);
    CHECK(contains(msg, "materials_file"));
    CHECK(contains(msg, "no_such_library.toml"));
  }
}

TEST_CASE("Case reader: a key given on top of a base overrides it", "[material][case]") {
  TempCaseDir tmp;
  const Scene sc = build_scene(minimal_case("base = \"aluminium\"\nyield_stress_MPa = 150.0"), "test", tmp.dir);
  REQUIRE(sc.materials.size() == 1);
  check_aluminium(sc.materials[0], 150e6);
  // the resolved case records the override and the base
  const auto* al = sc.resolved["materials"]["al"].as_table();
  REQUIRE(al);
  CHECK(al->get_as<double>("yield_stress_MPa")->get() == 150.0);
  CHECK(al->get_as<std::string>("base")->get() == "aluminium");
  // the body is filled with the material's density
  REQUIRE(sc.particles.size() > 0);
  CHECK(rel(sc.particles.m[0] / sc.particles.V[0], 2700.0) < 1e-12);
  // the other library entry
  const Scene cu = build_scene(minimal_case("base = \"copper\""), "test", tmp.dir);
  CHECK(model_name(cu.materials[0].eos) == "linear");
  CHECK(model_name(cu.materials[0].strength) == "elastic");
  CHECK(rel(cu.materials[0].E, 128e9) < 1e-15);
}

TEST_CASE("Case reader: overrides in another unit, of the model choice, unitless, and a bad base", "[material][case]") {
  TempCaseDir tmp;
  // another unit replaces the library's key
  const Scene a = build_scene(minimal_case("base = \"aluminium\"\nyield_stress_GPa = 0.15"), "test", tmp.dir);
  CHECK(rel(vmm(a.materials[0]).Y0, 150e6) < 1e-12);
  // a different strength part: the library's plasticity keys are not the case's business
  const Scene b = build_scene(minimal_case("base = \"aluminium\"\nstrength = \"elastic\""), "test", tmp.dir);
  CHECK(model_name(b.materials[0].strength) == "elastic");
  CHECK(model_name(b.materials[0].eos) == "mie_gruneisen");
  // ... but a key of the case's own that the chosen parts do not read is an error
  CHECK(contains(case_error(minimal_case("base = \"aluminium\"\nstrength = \"elastic\"\nyield_stress_MPa = 1.0"), tmp.dir),
                 "materials.al.yield_stress_MPa"));
  // a quantity without its unit
  CHECK(contains(case_error(minimal_case("base = \"aluminium\"\nyield_stress = 100.0"), tmp.dir), "needs its unit"));
  // base must be a name
  CHECK(contains(case_error(minimal_case("base = 3"), tmp.dir), "materials.al.base"));
  // the flow viscosity: absent, rate-independent; given in Pa s; negative, refused by name
  CHECK(vmm(a.materials[0]).eta == 0.0);
  const Scene v = build_scene(minimal_case("base = \"aluminium\"\nflow_viscosity_Pa_s = 1500.0"), "test", tmp.dir);
  CHECK(vmm(v.materials[0]).eta == 1500.0);
  const std::string msg = case_error(minimal_case("base = \"aluminium\"\nflow_viscosity_Pa_s = -1.0"), tmp.dir);
  INFO(msg);
  CHECK(contains(msg, "flow_viscosity_Pa_s"));
  CHECK(contains(msg, "out of range"));
}

// Every entry of the library (cases/materials.toml) with a Mie-Grueneisen EOS, read through the
// case reader: the code's dense Hugoniot lies on the entry's own line Us = c0 + s up. The entries
// are read from the file, so a new entry is tested without editing this test.
//
// Tolerance. On the Hugoniot e = P (V0 - V) / 2 cancels the Grueneisen term, and the code's
// Hugoniot pressure is the cubic C mu + D mu^2 + S mu^3 (mu = rho / rho0 - 1): the expansion to
// third order in mu of the line's P = rho0 c0^2 eta / (1 - s eta)^2, eta = mu / (1 + mu). The
// first term left out, rho0 c0^2 (s - 1)^2 (4 s - 1) mu^4, lowers P by the fraction
// eps = (s - 1)^2 (4 s - 1) mu^3 at a given compression. At that compression up and Us both scale
// with sqrt(P); back on the line at the same up, Us lies below it by est = eps / 2 * c0 / Us to
// leading order. Higher orders reduce it: (line - Us) / line is 0.99 est at up = 0.01 c0 and
// 0.78 est at 0.2 c0 for any s in [1.1, 2.2] (gamma0 drops out). Asserted, at up from 0.01 c0 to
// 0.2 c0: 0.7 est - 1e-7 <= (line - Us) / line <= est + 1e-7 (1e-7: the bisection of hugoniot()).
// For aluminium at 1 km/s est = 0.11 %; the code gives 0.090 % (docs/model.md: 0.1 %).
TEST_CASE("Library: every entry's dense Hugoniot lies on its own Us = c0 + s up line", "[material][hugoniot][case]") {
  const std::filesystem::path cases = std::filesystem::path(SHOCKMPM_SOURCE_DIR) / "cases";
  const toml::table lib = parse_case_file(cases / "materials.toml");
  int entries = 0;
  for (const auto& [key, node] : lib) {
    if (!node.is_table()) continue;
    const std::string name(key.str());
    INFO("library entry [" << name << "]");
    const Scene sc = build_scene(minimal_case("base = \"" + name + "\""), "test", cases);
    REQUIRE(sc.materials.size() == 1);
    const Material& m = sc.materials[0];
    if (!m.has_hugoniot()) continue;  // no Hugoniot line to check
    ++entries;
    // An entry valid only below a phase transition is tested below it: alpha iron up to the
    // alpha-epsilon transition at 13 GPa on the Hugoniot ([iron] in cases/materials.toml).
    const double P_max = name == "iron" ? 13e9 : 1e300;
    const double c0 = mg(m).c0, s = mg(m).s, rho0 = m.rho0;
    int points = 0;
    for (double x : {0.01, 0.02, 0.04, 0.06, 0.1, 0.15, 0.2}) {
      const double up = x * c0, Us_line = c0 + s * up;
      if (rho0 * Us_line * up >= P_max) continue;
      ++points;
      INFO("up = " << up << " m/s (" << x << " c0), line Us = " << Us_line << " m/s");
      const HugoniotState h = hugoniot(m, up);
      INFO("code: Us = " << h.Us << " m/s, P = " << h.P * 1e-9 << " GPa");
      REQUIRE(h.in_range);
      CHECK(rel(h.up, up) < 1e-6);
      CHECK(rel(h.P, rho0 * h.Us * h.up) < 1e-9);
      const double mu = up / (Us_line - up);  // rho / rho0 - 1 on the line
      const double est = 0.5 * (s - 1) * (s - 1) * (4 * s - 1) * mu * mu * mu * c0 / Us_line;
      const double below = (Us_line - h.Us) / Us_line;
      INFO("below the line by " << below * 100 << " %, leading-order estimate " << est * 100 << " %");
      CHECK(below <= est + 1e-7);
      CHECK(below >= 0.7 * est - 1e-7);
    }
    CHECK(points >= 4);
  }
  // the study's aluminium and the sourced entries (iron, copper, al1100, al2024, al6061)
  CHECK(entries >= 6);
}

TEST_CASE("heat fraction: the stored share of plastic work does not heat", "[material][thermo]") {
  Material m;
  m.name = "al";
  m.eos = MieGruneisenModel{5350.0, 1.34, 2.0};
  m.strength = VonMisesModel{120e6, 384e6};
  m.rho0 = 2700.0; m.E = 69e9; m.nu = 0.33;
  m.cv = 880.0; m.T0 = 300.0;
  Particles P;
  P.resize(1);
  P.m = {2.7e-9};
  P.V = {1e-12};
  P.e = {8800.0};   // would be 10 K of heating
  P.wp = {8800.0};  // all of it plastic work
  const Thermo th(m);
  m.heat_fraction = 1.0;
  const double T1 = particle_temperature(P, 0, th, m);
  m.heat_fraction = 0.9;
  const double T09 = particle_temperature(P, 0, th, m);
  CHECK(T1 - T09 == Approx(0.1 * 8800.0 / 880.0).epsilon(1e-12));  // 1 K less
  CHECK(T1 == Approx(310.0).epsilon(1e-6));
}

TEST_CASE("Jaumann trial step and von Mises norm match the 2x2 matrix expressions", "[material]") {
  // the kernel writes them out in scalars (SIMD-friendly); Eigen gives the reference
  using Mat2 = Eigen::Matrix2d;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < 100; ++k) {
    const double G = 26e9, dt = 1e-9;
    const double sxx = 1e8 * u(rng), syy = 1e8 * u(rng), sxy = 1e8 * u(rng);
    const double dxx = 1e7 * u(rng), dyy = 1e7 * u(rng), dxy = 1e7 * u(rng), w = 1e7 * u(rng);
    const Mat2 s = (Mat2() << sxx, sxy, sxy, syy).finished();
    const Mat2 D = (Mat2() << dxx, dxy, dxy, dyy).finished();
    const Mat2 W = (Mat2() << 0.0, w, -w, 0.0).finished();
    const Mat2 devD = D - (D.trace() / 3.0) * Mat2::Identity();
    const Mat2 ref = s + dt * (2.0 * G * devD + W * s - s * W);
    double a = sxx, b = syy, c = sxy;
    jaumann_trial(G, a, b, c, dxx, dyy, dxy, w, dt);
    CHECK(a == Approx(ref(0, 0)).epsilon(1e-13).margin(1e-3));
    CHECK(b == Approx(ref(1, 1)).epsilon(1e-13).margin(1e-3));
    CHECK(c == Approx(ref(0, 1)).epsilon(1e-13).margin(1e-3));
    CHECK(ref(0, 1) == Approx(ref(1, 0)).epsilon(1e-13).margin(1e-3));  // stays symmetric
    const double szz = -s.trace();
    CHECK(von_mises(sxx, syy, sxy) == Approx(std::sqrt(1.5 * (s.squaredNorm() + szz * szz))).epsilon(1e-14));
  }
}

TEST_CASE("A fractured point takes the work of the stress it carried, not of its trial deviator",
          "[material][constitutive]") {
  // A point expanded below rho0 / 2 (debris) with zero stress, stretching and shearing fast:
  // the trial deviator of the step never acts, so its energy must not change. Then a point
  // that fractures with a stress: it takes the centred work of that stress (old stress and 0).
  const Material al = aluminium();
  const auto eos = al.gruneisen().value();
  const kern::VonMisesStrength vm{al.shear_modulus(), vmm(al).Y0, vmm(al).H};
  const double V0 = 1e-10;
  double x = 0, y = 0, vx = 0, vy = 0, m = 0.4 * al.rho0 * V0, V = V0, sxx = 0, syy = 0, sxy = 0, p = 0;
  double Lxx = 2e7, Lxy = 3e7, Lyx = -1e7, Lyy = 1e7;
  double e = 1e5, epsp = 0.3, qv = 0;
  const kern::ParticleView P{&x,   &y,   &vx, &vy, &m,      &V,      &sxx,
                             &syy, &sxy, &p,  nullptr, nullptr, nullptr, nullptr, &qv, &e};
  kern::Gradient Lg;
  Lg.L[0] = &Lxx, Lg.L[1] = &Lxy, Lg.L[2] = &Lyx, Lg.L[3] = &Lyy;
  const kern::ConstitutiveState S{&e, &epsp, &qv, nullptr};
  kern::ConstitutiveParams q;
  q.dt = 1e-10;
  q.p_min = -1e9;  // the library's spall strength (cases/materials.toml)
  q.rho_min = 0.5 * al.rho0;
  q.av_length = 4e-6;
  q.av_linear = 0.06;
  q.av_quadratic = 1.5;
  for (int k = 0; k < 50; ++k) {
    const auto r = kern::constitutive_update(P, S, Lg, 1, q, eos, vm);
    REQUIRE(r.bad == -1);
  }
  CHECK(V == V0);   // debris does not expand further (unguarded, its volume grows without bound)
  CHECK(e == 1e5);  // no energy from nothing (unguarded: 1e14 J/kg in 400 ns)
  CHECK(sxx == 0.0);
  CHECK(syy == 0.0);
  CHECK(sxy == 0.0);
  CHECK(p == 0.0);

  // ... but it compresses, and carries pressure again once packed above rho_min
  Lxx = -2e8, Lxy = 0, Lyx = 0, Lyy = -2e8;
  for (int k = 0; k < 200 && m / V < q.rho_min; ++k) {
    kern::constitutive_update(P, S, Lg, 1, q, eos, vm);
    CHECK(p == 0.0);
  }
  REQUIRE(m / V >= q.rho_min);
  Lxx = -5e8, Lyy = -5e8;
  for (int k = 0; k < 200 && m / V < al.rho0 * 1.05; ++k) kern::constitutive_update(P, S, Lg, 1, q, eos, vm);
  CHECK(m / V > al.rho0);
  CHECK(p > 0.0);

  // fracture from a stressed state: energy changes by the centred work of the old stress
  m = 0.55 * al.rho0 * V0;  // rho just above rho0 / 2: the expansion takes it below
  V = V0;
  sxx = 1e8, syy = -5e7, sxy = 2e7, p = -2e8;
  e = 1e5;
  Lxx = 5e8, Lxy = 0, Lyx = 0, Lyy = 5e8;  // fast expansion: rho drops below rho0 / 2
  const double a0 = sxx, b0 = syy, c0 = sxy, P0 = p;
  kern::constitutive_update(P, S, Lg, 1, q, eos, vm);
  REQUIRE(m / V < q.rho_min);
  const double dV = V - V0, dxy = 0.0;
  const double expect = 1e5 + (q.dt * 0.5 * (V0 + V) * 0.5 * (a0 * Lxx + b0 * Lyy + 2 * c0 * dxy) - 0.5 * P0 * dV) / m;
  CHECK(e == Approx(expect).epsilon(1e-14));
  CHECK(p == 0.0);
}

// The fully compacted porous Hugoniot (run.json "compacted_hugoniot", the front a converged
// porous run approaches): porosity 0 is the dense Hugoniot; at porosity 0.5 the state satisfies
// the three jump conditions from (rho00, 0, 0) and the EOS.
TEST_CASE("fully compacted porous Hugoniot satisfies the jump conditions and the EOS", "[material][hugoniot]") {
  const Material al = aluminium();
  const auto d = hugoniot(al, 1000.0), z = porous_hugoniot(al, 1000.0, 0.0);
  REQUIRE(z.in_range);
  CHECK(z.Us == Approx(d.Us).epsilon(1e-9));
  CHECK(z.P == Approx(d.P).epsilon(1e-9));
  for (double phi : {0.1, 0.3, 0.45, 0.501}) {
    const auto c = porous_hugoniot(al, 1000.0, phi);
    REQUIRE(c.in_range);
    const double rho00 = (1 - phi) * al.rho0;
    CHECK(c.up == Approx(1000.0).epsilon(1e-9));
    CHECK(rho00 * c.Us == Approx(c.rho * (c.Us - c.up)).epsilon(1e-9));        // mass
    CHECK(c.P == Approx(rho00 * c.Us * c.up).epsilon(1e-9));                    // momentum
    CHECK(c.e == Approx(0.5 * c.up * c.up).epsilon(1e-9));                      // energy
    CHECK(c.P == Approx(al.gruneisen().value().pressure(c.rho, c.e)).epsilon(1e-9));  // EOS
    WARN("porosity " << phi << ": compaction front " << c.Us - c.up << " m/s (wall frame), P " << c.P * 1e-9
                     << " GPa, rho " << c.rho << " kg/m^3");
  }
  // near porosity 0.5 with gamma0 = 2 the compacted state sits at rho0 itself: the front is the
  // snowplow speed up rho00 / (rho0 - rho00) (exactly 0.5 is degenerate: no state with P > 0)
  const auto c = porous_hugoniot(al, 1000.0, 0.501);
  CHECK(c.rho < al.rho0);
  CHECK(c.Us - c.up == Approx(1000.0 * 0.499 / 0.501).epsilon(1e-3));
  // a state on both sides of 0.5 and through the near-degenerate band (a scan bracket that ended
  // at rho0, where P = 0, was once refused: no state at 0.4945 and 0.4966 at 1000 m/s), and the
  // front slows as porosity grows
  for (double up : {500.0, 1000.0, 2000.0}) {
    double last = 1e300;
    for (double phi = 0.46; phi < 0.54; phi += 0.0015) {
      if (std::abs(phi - 0.5) < 1e-6) continue;
      const auto s = porous_hugoniot(al, up, phi);
      INFO("up " << up << " m/s, porosity " << phi);
      REQUIRE(s.in_range);
      CHECK(s.P == Approx((1 - phi) * al.rho0 * s.Us * s.up).epsilon(1e-9));
      CHECK(s.Us - s.up < last);
      last = s.Us - s.up;
    }
    // within 1e-4 of 0.5 the pressure's pole sits within the scans' step of rho0 (the study's
    // 5 um void case, porosity 0.50002, had no state): the snowplow front v rho00 / (rho0 - rho00)
    for (double d : {-5e-4, -1e-4, -2e-5, -1e-6, 1e-6, 2e-5, 1e-4, 5e-4}) {
      const double phi = 0.5 + d;
      const auto s = porous_hugoniot(al, up, phi);
      INFO("up " << up << " m/s, porosity " << phi);
      REQUIRE(s.in_range);
      CHECK(s.P == Approx((1 - phi) * al.rho0 * s.Us * s.up).epsilon(1e-9));
      CHECK(s.Us - s.up == Approx(up * (1 - phi) / phi).epsilon(0.01));
    }
  }
}
