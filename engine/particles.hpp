// Particle state: structure of arrays, one contiguous array per field. A scene allocates only
// the fields its models need: the optional ones below stay empty unless enabled
// (Particles::enable, enable_affine; fields_in_use lists those allocated).
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "kernels/views.hpp"

namespace smpm {

struct Particles {
  // Always present.
  std::vector<double> x, y;       // position [m]
  std::vector<double> vx, vy;     // velocity [m/s]
  std::vector<double> m;          // mass per unit thickness [kg/m]
  std::vector<double> V;          // current volume per unit thickness [m^2]
  std::vector<double> sxx, syy, sxy;  // stress deviator [Pa] (s_zz = -(s_xx + s_yy))
  std::vector<double> p;          // pressure [Pa], compression positive
  std::vector<double> Lxx, Lxy, Lyx, Lyy;  // velocity gradient [1/s]
  // Optional: sized 0 unless the scene needs them.
  std::vector<double> Cxx, Cxy, Cyx, Cyy;  // APIC affine matrix [1/s]
  std::vector<double> e;      // specific internal energy [J/kg] (energy-dependent EOS)
  std::vector<double> epsp;   // equivalent plastic strain [-] (plastic strength)
  std::vector<double> q;      // artificial viscous pressure [Pa] (artificial viscosity on)
  std::vector<double> wp;     // plastic work per mass [J/kg] (heat fraction below 1)
  std::vector<std::uint32_t> id;  // original index, permuted along with the rest
  std::vector<std::uint8_t> body; // body index
  // Velocity field of each point when the grid has several (two-body contact: the body;
  // separated void faces: the side of its nearest void, assign_void_sides); else empty.
  std::vector<std::uint8_t> field;

  std::size_t size() const { return x.size(); }
  // Component arrays by axis: position and velocity (axis d), stress deviator (symmetric
  // component k, kernels/tensor.hpp's order), velocity gradient and affine matrix (row r,
  // column c).
  std::vector<double>& pos(int d) { return d == 0 ? x : y; }
  const std::vector<double>& pos(int d) const { return d == 0 ? x : y; }
  std::vector<double>& vel(int d) { return d == 0 ? vx : vy; }
  const std::vector<double>& vel(int d) const { return d == 0 ? vx : vy; }
  std::vector<double>& dev(int k) { return k == 0 ? sxx : k == 1 ? syy : sxy; }
  const std::vector<double>& dev(int k) const { return k == 0 ? sxx : k == 1 ? syy : sxy; }
  std::vector<double>& grad(int r, int c) { return r == 0 ? (c == 0 ? Lxx : Lxy) : (c == 0 ? Lyx : Lyy); }
  std::vector<double>& affine(int r, int c) { return r == 0 ? (c == 0 ? Cxx : Cxy) : (c == 0 ? Cyx : Cyy); }
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
  // f(name, array) for every array in use, in the order of fields_in_use (checkpoints).
  template <class F>
  void each_array(F&& f) {
    const char* names[] = {"x", "y", "vx", "vy", "m", "V", "sxx", "syy", "sxy", "p", "Lxx", "Lxy", "Lyx", "Lyy",
                           "Cxx", "Cxy", "Cyx", "Cyy", "e", "epsp", "q", "wp"};
    std::vector<double>* arrays[] = {&x, &y, &vx, &vy, &m, &V, &sxx, &syy, &sxy, &p, &Lxx, &Lxy, &Lyx, &Lyy,
                                     &Cxx, &Cxy, &Cyx, &Cyy, &e, &epsp, &q, &wp};
    for (int k = 0; k < 22; ++k)
      if (k < 14 || !arrays[k]->empty()) f(names[k], *arrays[k]);
    f("id", id);
    f("body", body);
    if (!field.empty()) f("field", field);
  }
  void append(const Particles& o);
};

}  // namespace smpm
