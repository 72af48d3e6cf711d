// A material is assembled from models chosen by name in the case file: an equation of state
// (pressure), a strength model (deviatoric stress), and thermal data (temperature, heating,
// conduction). Each EOS and strength model is one struct below: its name, its case-file keys
// with their ranges and defaults (read), its kernel part (part: the per-point update of
// kernels/constitutive.hpp) and its thermodynamics; the lists EosModel and StrengthModel
// register them. with_material() maps the run-time choice onto the templated constitutive
// kernel, once per range of points, so a scene pays only for the parts it uses.
#pragma once
#include "kernels/dimension.hpp"
#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "kernels/constitutive.hpp"

// Units of case-file quantities (engine/case_reader.hpp).
namespace smpm {
struct Quantity;
extern const Quantity kVelocity, kStress, kViscosity;
}  // namespace smpm

namespace SMPM_NS {

// The elastic constants every material has; the models derive their parts from them.
struct ElasticConstants {
  double rho0 = 0.0;  // reference density [kg/m^3]
  double E = 0.0;     // Young's modulus [Pa]
  double nu = 0.0;    // Poisson's ratio [-]
  double shear_modulus() const { return E / (2.0 * (1.0 + nu)); }
};

// ---- EOS models ------------------------------------------------------------------------------
// Each: name; read(r) its keys (r a CaseReader); part(c) its kern:: EOS part; bulk_modulus(c)
// at rho0; gruneisen(c), the EOS in the form P = cold(rho) + Gamma rho e from which the engine
// takes temperatures and Hugoniot states (none: simple temperature only, no Hugoniot);
// zero_pressure_density(c, e).

// P = K (rho / rho0 - 1), K = E / (3 (1 - 2 nu)).
struct LinearEosModel {
  static constexpr const char* name = "linear";
  bool operator==(const LinearEosModel&) const = default;
  template <class Reader>
  void read(Reader&) {}
  kern::LinearEos part(const ElasticConstants& c) const { return {c.rho0, bulk_modulus(c)}; }
  double bulk_modulus(const ElasticConstants& c) const { return c.E / (3.0 * (1.0 - 2.0 * c.nu)); }
  std::optional<kern::MieGruneisenEos> gruneisen(const ElasticConstants&) const { return std::nullopt; }
  double zero_pressure_density(const ElasticConstants& c, double) const { return c.rho0; }
};

// Mie-Grueneisen with a linear Us-up Hugoniot (kern::MieGruneisenEos).
struct MieGruneisenModel {
  static constexpr const char* name = "mie_gruneisen";
  bool operator==(const MieGruneisenModel&) const = default;
  double c0 = 0.0;      // bulk sound speed [m/s]
  double s = 0.0;       // Hugoniot slope dUs/dup [-]
  double gamma0 = 0.0;  // Grueneisen gamma at rho0 [-]
  template <class Reader>
  void read(Reader& r) {
    c0 = r.quantity("bulk_sound_speed", kVelocity, 1e-6, 1e6);
    s = r.number("hugoniot_slope", 0.0, 10.0);
    gamma0 = r.number("gruneisen_gamma", 0.0, 10.0);
  }
  kern::MieGruneisenEos part(const ElasticConstants& c) const { return kern::MieGruneisenEos::make(c.rho0, c0, s, gamma0); }
  double bulk_modulus(const ElasticConstants& c) const { return c.rho0 * c0 * c0; }
  std::optional<kern::MieGruneisenEos> gruneisen(const ElasticConstants& c) const { return part(c); }
  double zero_pressure_density(const ElasticConstants& c, double e) const { return part(c).zero_pressure_density(e); }
};

// ---- strength models -------------------------------------------------------------------------
// Each: name; read(r) its keys; part(c) its kern:: strength part.

struct NoStrengthModel {
  static constexpr const char* name = "none";
  bool operator==(const NoStrengthModel&) const = default;
  template <class Reader>
  void read(Reader&) {}
  kern::NoStrength part(const ElasticConstants&) const { return {}; }
};

struct ElasticStrengthModel {
  static constexpr const char* name = "elastic";
  bool operator==(const ElasticStrengthModel&) const = default;
  template <class Reader>
  void read(Reader&) {}
  kern::ElasticStrength part(const ElasticConstants& c) const { return {c.shear_modulus()}; }
};

// von Mises with linear isotropic hardening and an optional flow viscosity: flow stress
// Y0 + H eps_p + 3 eta d(eps_p)/dt (kern::VonMisesStrength); eta = 0, the default, is
// rate-independent.
struct VonMisesModel {
  static constexpr const char* name = "von_mises";
  bool operator==(const VonMisesModel&) const = default;
  double Y0 = 0.0;   // initial yield stress [Pa]
  double H = 0.0;    // linear hardening modulus [Pa]
  double eta = 0.0;  // flow viscosity [Pa s]
  template <class Reader>
  void read(Reader& r) {
    Y0 = r.quantity("yield_stress", kStress, 0.0, 1e15);
    H = r.quantity("hardening_modulus", kStress, 0.0, 1e15);
    eta = r.quantity("flow_viscosity", kViscosity, 0.0, 1e9, 0.0);
  }
  kern::VonMisesStrength part(const ElasticConstants& c) const { return {c.shear_modulus(), Y0, H, eta}; }
};

// ---- the registry: one line per model (the case files' names in this order in messages) -----

using EosModel = std::variant<LinearEosModel, MieGruneisenModel>;
using StrengthModel = std::variant<NoStrengthModel, ElasticStrengthModel, VonMisesModel>;

// The names of a registry's models, in its order.
template <class Registry>
std::vector<std::string> model_names() {
  return []<std::size_t... I>(std::index_sequence<I...>) {
    return std::vector<std::string>{std::variant_alternative_t<I, Registry>::name...};
  }(std::make_index_sequence<std::variant_size_v<Registry>>{});
}

// The model of a registry named `name` (default parameters); the first one when none is.
template <class Registry>
Registry model_named(const std::string& name) {
  Registry out;
  [&]<std::size_t... I>(std::index_sequence<I...>) {
    ((name == std::variant_alternative_t<I, Registry>::name ? (out = std::variant_alternative_t<I, Registry>{}, 0) : 0),
     ...);
  }(std::make_index_sequence<std::variant_size_v<Registry>>{});
  return out;
}

// The name of the model a registry variant holds.
template <class Registry>
std::string model_name(const Registry& m) {
  return std::visit([](const auto& model) { return std::string(model.name); }, m);
}

enum class TemperatureKind { Isentrope, Simple };

struct Material : ElasticConstants {
  std::string name;
  EosModel eos = LinearEosModel{};
  StrengthModel strength = ElasticStrengthModel{};
  // Tension limit (spall): a point whose pressure would fall below -spall_strength has
  // fractured: no pressure and no deviatoric stress until it is compressed again. 0: none.
  double spall_strength = 0.0;  // [Pa]
  // thermal
  double cv = 0.0;             // specific heat [J/(kg K)]
  double conductivity = 0.0;   // thermal conductivity [W/(m K)]
  double T0 = 300.0;           // initial temperature [K]
  double heat_fraction = 1.0;  // fraction of plastic work that heats (the rest is stored)
  TemperatureKind temperature = TemperatureKind::Isentrope;

  // Bulk modulus at rho0 (the EOS model's).
  double bulk_modulus() const {
    return std::visit([this](const auto& m) { return m.bulk_modulus(*this); }, eos);
  }
  // The EOS part's pressure depends on the specific internal energy: the points carry it.
  bool needs_energy() const {
    return std::visit([this](const auto& m) { return decltype(m.part(*this))::needs_energy; }, eos);
  }
  // The strength part has a plastic strain (and plastic work).
  bool plastic() const {
    return std::visit([this](const auto& m) { return decltype(m.part(*this))::plastic; }, strength);
  }
  // The EOS in Mie-Grueneisen form (temperature tables, Hugoniot states); none for an EOS
  // without one.
  std::optional<kern::MieGruneisenEos> gruneisen() const {
    return std::visit([this](const auto& m) { return m.gruneisen(*this); }, eos);
  }
  bool has_hugoniot() const { return gruneisen().has_value(); }
  // Density at zero pressure for the specific internal energy e [J/kg].
  double zero_pressure_density(double e) const {
    return std::visit([this, e](const auto& m) { return m.zero_pressure_density(*this, e); }, eos);
  }
  // Elastic strain energy per unit volume of a stress state (for materials without an energy
  // field: linear EOS, elastic or no strength); at D = 2 with s_zz = -(s_xx + s_yy).
  double strain_energy_density(kern::Sym<kern::kDim> s, double p) const {
    const double G = shear_modulus();
    return (G > 0 ? deviator_square(s) / (4.0 * G) : 0.0) + p * p / (2.0 * bulk_modulus());
  }

 private:
  // s : s, summed as s_xx^2 + s_yy^2 + s_zz^2 + 2 s_xy^2 (+ 2 s_xz^2 + 2 s_yz^2)
  static double deviator_square(kern::Sym<kern::kDim> s) {
    constexpr int D = kern::kDim;
    double sum = s[0] * s[0];
    for (int d = 1; d < D; ++d) sum += s[d] * s[d];
    if constexpr (D == 2) {
      const double closure = -(s[0] + s[1]);  // the out-of-plane entry
      sum += closure * closure;
    }
    for (int k = D; k < kern::Sym<D>::K; ++k) sum += 2.0 * s[k] * s[k];
    return sum;
  }
};

// Calls f(eos_part, strength_part) with the parts of `mat`.
template <class F>
decltype(auto) with_material(const Material& mat, F&& f) {
  return std::visit([&](const auto& e, const auto& s) { return f(e.part(mat), s.part(mat)); }, mat.eos, mat.strength);
}

// kern::constitutive_block with the parts of `mat`: the constitutive update of points
// [first, last).
using ConstitutiveFn = kern::ConstitutiveResult (*)(const Material&, const kern::ParticleView&,
                                                    const kern::ConstitutiveState&, const kern::Gradient&,
                                                    std::size_t, std::size_t, const kern::ConstitutiveParams&,
                                                    kern::Selection);

// The update for a material whose EOS model is Model, every strength model.
template <class Model>
kern::ConstitutiveResult constitutive_model(const Material& mat, const kern::ParticleView& P,
                                            const kern::ConstitutiveState& S, const kern::Gradient& L,
                                            std::size_t first, std::size_t last, const kern::ConstitutiveParams& q,
                                            kern::Selection sel) {
  const auto eos = std::get<Model>(mat.eos).part(mat);
  return std::visit(
      [&](const auto& s) { return kern::constitutive_block(P, S, L, first, last, q, eos, s.part(mat), sel); },
      mat.strength);
}

// The updates of the EOS models i with i % 2 == Share (index i in EosModel; null for the
// others). Compiled in engine/constitutive_share0.cpp and engine/constitutive_share1.cpp, apart
// from the engine's other code, so that the vectorized loops of every combination build in two
// parallel halves and an edit elsewhere does not rebuild them.
template <std::size_t I, int Share>
constexpr ConstitutiveFn constitutive_entry() {
  if constexpr (I % 2 == Share) return &constitutive_model<std::variant_alternative_t<I, EosModel>>;
  else return nullptr;
}
template <int Share>
const ConstitutiveFn* constitutive_share() {
  static constexpr auto table = []<std::size_t... I>(std::index_sequence<I...>) {
    return std::array<ConstitutiveFn, sizeof...(I)>{constitutive_entry<I, Share>()...};
  }(std::make_index_sequence<std::variant_size_v<EosModel>>{});
  return table.data();
}
extern template const ConstitutiveFn* constitutive_share<0>();
extern template const ConstitutiveFn* constitutive_share<1>();

inline kern::ConstitutiveResult constitutive_block(const Material& mat, const kern::ParticleView& P,
                                                   const kern::ConstitutiveState& S, const kern::Gradient& L,
                                                   std::size_t first, std::size_t last,
                                                   const kern::ConstitutiveParams& q, kern::Selection sel) {
  const std::size_t i = mat.eos.index();
  const ConstitutiveFn* updates = i % 2 == 0 ? constitutive_share<0>() : constitutive_share<1>();
  return updates[i](mat, P, S, L, first, last, q, sel);
}

}  // namespace SMPM_NS
