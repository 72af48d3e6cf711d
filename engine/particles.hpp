// Particle state: structure of arrays, one contiguous array per field. A scene allocates only
// the fields its models need: the optional ones below stay empty unless enabled
// (Particles::enable, enable_affine; fields_in_use lists those allocated).
#pragma once
#include "kernels/dimension.hpp"
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "kernels/views.hpp"

namespace SMPM_NS {

inline constexpr int kSym = kern::sym_size(kern::kDim);  // symmetric tensor components

// The name of one particle array: a stem and up to two axis indices ("x", "vy", "sxy", "Lyx").
struct FieldName {
  const char* stem;
  int r = -1, c = -1;
  std::string str() const {
    std::string n = stem;
    for (const int a : {r, c})
      if (a >= 0) n += kern::kAxisNames[a];
    return n;
  }
};

struct Particles {
  // Always present. Vector and tensor fields are one array per component: x[d], v[d] by axis;
  // s[k] by symmetric component (kernels/tensor.hpp's order: xx, yy, xy at D = 2); C row major,
  // C[r * kern::kDim + c].
  std::vector<double> x[kern::kDim];    // position [m]
  std::vector<double> v[kern::kDim];    // velocity [m/s]
  std::vector<double> m;          // mass per unit thickness [kg/m]
  std::vector<double> V;          // current volume per unit thickness [m^2]
  std::vector<double> s[kSym];    // stress deviator [Pa] (at D = 2, s_zz = -(s_xx + s_yy))
  std::vector<double> p;          // pressure [Pa], compression positive
  // What the regional statistics read of the velocity gradient L (diagnostics.hpp), as the last
  // step that stored it left it (Simulation::store_gradient): L itself is never stored.
  std::vector<double> curl2;  // |curl v|^2 [1/s^2]
  std::vector<double> div;    // div v = tr L [1/s]
  std::vector<double> rate2;  // sym L : sym L [1/s^2]
  // Optional: sized 0 unless the scene needs them.
  std::vector<double> C[kern::kDim * kern::kDim];  // APIC affine matrix [1/s]
  std::vector<double> e;      // specific internal energy [J/kg] (energy-dependent EOS)
  std::vector<double> epsp;   // equivalent plastic strain [-] (plastic strength)
  std::vector<double> q;      // artificial viscous pressure [Pa] (artificial viscosity on)
  std::vector<double> wp;     // plastic work per mass [J/kg] (heat fraction below 1)
  std::vector<std::uint32_t> id;  // original index, permuted along with the rest
  std::vector<std::uint8_t> body; // body index
  // Velocity field of each point when the grid has several (two-body contact: the body;
  // separated void faces: the side of its nearest void, assign_void_sides); else empty.
  std::vector<std::uint8_t> field;

  std::size_t size() const { return x[0].size(); }
  // The affine matrix by row r and column c.
  std::vector<double>& affine(int r, int c) { return C[r * kern::kDim + c]; }
  const std::vector<double>& affine(int r, int c) const { return C[r * kern::kDim + c]; }
  void resize(std::size_t n);  // resizes the fields in use (optional ones only when enabled)
  void enable_affine(bool on);  // allocate (zeroed) or release the APIC matrix
  // allocate (zeroed) or release one optional scalar field
  static void enable(std::vector<double>& field, std::size_t n, bool on);
  kern::ParticleView view();
  // Physically reorders every array so that array order becomes `order` (sorted order). The
  // scratch vectors are resized to size() once and then reused: no allocation per permutation.
  void permute(const std::uint32_t* order, std::vector<double>& scratch_d,
               std::vector<std::uint32_t>& scratch_u, std::vector<std::uint8_t>& scratch_b);
  // Resident bytes of all particle arrays.
  std::size_t bytes() const;
  // Names of the arrays in use (the optional ones only when allocated), as in this struct.
  std::vector<std::string> fields_in_use() const;
  // f(name, array) for every array in use, in the order of fields_in_use (checkpoints): x, y,
  // vx, vy, m, V, sxx, syy, sxy, p, curl2, div, rate2, then the optional Cxx .. Cyy, e, epsp, q,
  // wp when allocated, then id, body and (when used) field.
  template <class F>
  void each_array(F&& f) {
    for_each_double([&](const FieldName& n, std::vector<double>& a) { f(n.str().c_str(), a); });
    f("id", id);
    f("body", body);
    if (!field.empty()) f("field", field);
  }
  // f(name, array) for every double array in use (the optional ones only when allocated).
  template <class F>
  void for_each_double(F&& f) {
    constexpr int D = kern::kDim;
    for (int d = 0; d < D; ++d) f(FieldName{"", d}, x[d]);
    for (int d = 0; d < D; ++d) f(FieldName{"v", d}, v[d]);
    f(FieldName{"m"}, m);
    f(FieldName{"V"}, V);
    for (int k = 0; k < kSym; ++k) f(FieldName{"s", kern::sym_row(D, k), kern::sym_col(D, k)}, s[k]);
    f(FieldName{"p"}, p);
    f(FieldName{"curl2"}, curl2);
    f(FieldName{"div"}, div);
    f(FieldName{"rate2"}, rate2);
    for (int k = 0; k < D * D; ++k)
      if (!C[k].empty()) f(FieldName{"C", k / D, k % D}, C[k]);
    for (auto [stem, a] : {std::pair{"e", &e}, {"epsp", &epsp}, {"q", &q}, {"wp", &wp}})
      if (!a->empty()) f(FieldName{stem}, *a);
  }
  void append(const Particles& o);
};

}  // namespace SMPM_NS
