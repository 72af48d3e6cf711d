#include "kernels/dimension.hpp"
#include "engine/thermo.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace SMPM_NS {

namespace {
constexpr int kTable = 8192;
}

Thermo::Thermo(const Material& m) : m_(m) {
  const auto form = m.gruneisen();
  if (!form) return;  // simple temperature only
  const kern::MieGruneisenEos eos = *form;
  gamma0_ = eos.gamma0;
  if (m.spall_strength > 0.0) rho_spall_ = m.rho0 * (1.0 - m.spall_strength / eos.C);  // cold P = -spall
  const double V0 = 1.0 / m.rho0;
  d_ = (kEtaMax - kEtaMin) / (kTable - 1);
  es_.assign(kTable, 0.0);
  // de/deta = -P dV/deta = P V0 (V = V0 (1 - eta)); integrate from eta = 0 both ways.
  auto rhs = [&](double eta, double e) { return eos.pressure(m.rho0 / (1.0 - eta), e) * V0; };
  const int i0 = static_cast<int>(std::lround(-kEtaMin / d_));
  const double eta_at_i0 = kEtaMin + i0 * d_;
  // first step from eta = 0 to the grid point i0 (grid may not contain 0 exactly)
  auto rk4 = [&](double eta, double e, double h) {
    const double k1 = rhs(eta, e), k2 = rhs(eta + h / 2, e + h / 2 * k1), k3 = rhs(eta + h / 2, e + h / 2 * k2),
                 k4 = rhs(eta + h, e + h * k3);
    return e + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
  };
  es_[i0] = rk4(0.0, 0.0, eta_at_i0);
  for (int i = i0 + 1; i < kTable; ++i) es_[i] = rk4(kEtaMin + (i - 1) * d_, es_[i - 1], d_);
  for (int i = i0 - 1; i >= 0; --i) es_[i] = rk4(kEtaMin + (i + 1) * d_, es_[i + 1], -d_);
}

double Thermo::isentrope_energy(double rho) const {
  if (es_.empty()) return 0.0;
  const double eta = 1.0 - m_.rho0 / rho;
  double f = (eta - kEtaMin) / d_;
  int i = static_cast<int>(std::floor(f));
  i = std::max(0, std::min(kTable - 2, i));
  f -= i;
  return es_[i] + f * (es_[i + 1] - es_[i]);
}

double Thermo::isentrope_temperature(double rho) const {
  return m_.T0 * std::exp(gamma0_ * (1.0 - m_.rho0 / rho));
}

double Thermo::temperature(double rho, double e, double stored) const {
  if (m_.cv <= 0.0) return m_.T0;
  const double heat = e - stored;
  if (m_.temperature == TemperatureKind::Simple || es_.empty()) return m_.T0 + heat / m_.cv;
  // With a spall limit, states expanded past it are fractured points that carry no tension
  // (docs/method.md): they are taken at the spall density, else the tension branch of the
  // isentrope would count their tension work as recoverable and make them cold, even negative.
  const double r = std::max(rho, rho_spall_);
  return isentrope_temperature(r) + (heat - isentrope_energy(r)) / m_.cv;
}

namespace {
// The state behind the shock from its density and pressure, the material ahead at rest at
// (rho00, P = 0, e = 0): particle and shock speeds, energy, temperatures.
HugoniotState jump_state(const Material& m, double rho00, double rho, double P) {
  HugoniotState h;
  const double dV = 1.0 / rho00 - 1.0 / rho;
  h.rho = rho;
  h.P = P;
  h.up = std::sqrt(std::max(0.0, P * dV));
  h.Us = h.P / (rho00 * h.up);
  h.e = 0.5 * h.P * dV;
  Material simple = m;
  simple.temperature = TemperatureKind::Simple;
  h.T = Thermo(m).temperature(h.rho, h.e);
  h.T_simple = Thermo(simple).temperature(h.rho, h.e);
  return h;
}
}  // namespace

HugoniotState hugoniot(const Material& m, double up) {
  const auto form = m.gruneisen();
  if (!form) throw std::invalid_argument("hugoniot: material " + m.name + " has no Mie-Grueneisen EOS");
  const kern::MieGruneisenEos eos = *form;
  const double V0 = 1.0 / m.rho0;
  // On the Hugoniot e = P (V0 - V) / 2, so P = cold / (1 - gamma_rho (V0 - V) / 2); up^2 = P (V0 - V).
  auto state = [&](double rho, double& P) {
    const double dV = V0 - 1.0 / rho;
    P = eos.cold(rho) / (1.0 - 0.5 * eos.gamma_rho() * dV);
    return std::sqrt(std::max(0.0, P * dV));
  };
  // the bracket: up to 4 rho0 (eta = 0.75, the end of the isentrope table) and below the
  // compression where 1 - gamma_rho (V0 - V) / 2 reaches 0
  double hi = 4.0 * m.rho0 * (1.0 - 1e-12);
  const double V_sing = V0 - 2.0 / eos.gamma_rho();
  if (V_sing > 0.0) hi = std::min(hi, (1.0 - 1e-9) / V_sing);
  double lo = m.rho0, P = 0;
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    (state(mid, P) < up ? lo : hi) = mid;
  }
  const double rho = 0.5 * (lo + hi);
  state(rho, P);
  HugoniotState h = jump_state(m, m.rho0, rho, P);
  h.in_range = std::abs(h.up - up) <= 1e-6 * up;
  return h;
}

HugoniotState porous_hugoniot(const Material& m, double up, double porosity) {
  const auto form = m.gruneisen();
  if (!form) throw std::invalid_argument("porous_hugoniot: material " + m.name + " has no Mie-Grueneisen EOS");
  if (!(porosity >= 0.0 && porosity < 1.0)) throw std::invalid_argument("porous_hugoniot: porosity must be in [0, 1)");
  const kern::MieGruneisenEos eos = *form;
  const double rho00 = (1.0 - porosity) * m.rho0, V00 = 1.0 / rho00;
  // f(rho) = P (V00 - V) - up^2 with P = cold / (1 - gamma_rho (V00 - V) / 2) (e on the Hugoniot)
  auto pressure = [&](double rho) {
    const double dV = V00 - 1.0 / rho;
    return eos.cold(rho) / (1.0 - 0.5 * eos.gamma_rho() * dV);
  };
  auto f = [&](double rho) {
    const double P = pressure(rho);
    return P > 0.0 ? P * (V00 - 1.0 / rho) - up * up : -up * up;
  };
  // scan from full density outwards (denser first, then lighter down to rho00) for a sign change
  // on the branch P > 0, then bisect
  HugoniotState h;
  h.in_range = false;
  double root = 0.0;
  const int n = 4000;
  auto try_bracket = [&](double a, double b) {
    if (!(f(a) < 0.0 && f(b) > 0.0) && !(f(a) > 0.0 && f(b) < 0.0)) return false;
    // on the branch P >= 0 (P = 0 exactly at rho0, where the scans start: a root just off rho0,
    // e.g. porosity 0.495 at 1000 m/s, lies in a bracket that ends there)
    if (!(pressure(a) >= 0.0 && pressure(b) >= 0.0)) return false;
    for (int it = 0; it < 200; ++it) {
      const double mid = 0.5 * (a + b);
      ((f(mid) < 0.0) == (f(a) < 0.0) ? a : b) = mid;
    }
    root = 0.5 * (a + b);
    return true;
  };
  bool found = false;
  for (int k = 0; k < n && !found; ++k) {  // denser than rho0, up to 4 rho0
    const double a = m.rho0 * (1.0 + 3.0 * k / n), b = m.rho0 * (1.0 + 3.0 * (k + 1) / n);
    found = try_bracket(a, b);
  }
  for (int k = 0; k < n && !found; ++k) {  // lighter than rho0 (hot), down to rho00
    const double b = m.rho0 - (m.rho0 - rho00) * k / n, a = m.rho0 - (m.rho0 - rho00) * (k + 1) / n;
    found = try_bracket(a, b);
  }
  // porosity within about 1e-4 of the degenerate one (0.5 for gamma0 = 2: the pressure's pole
  // V00 - V = 2 / gamma_rho then sits next to rho0, and the state between the pole and rho0 is
  // narrower than the scans' steps): brackets shrinking geometrically towards rho0 on each side
  for (int k = 0; k < 240 && !found; ++k) {
    const double d0 = std::pow(10.0, -3.0 - k / 20.0), d1 = std::pow(10.0, -3.0 - (k + 1) / 20.0);
    found = try_bracket(m.rho0 * (1.0 + d1), m.rho0 * (1.0 + d0)) || try_bracket(m.rho0 * (1.0 - d0), m.rho0 * (1.0 - d1));
  }
  if (!found) return h;
  return jump_state(m, rho00, root, pressure(root));
}

}  // namespace SMPM_NS
