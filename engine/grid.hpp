// Background grid storage: node arrays over the padded node range of kern::GridGeom (the
// velocity fields' arrays kern::kLinePad doubles longer), vector quantities one array per axis,
// and the halo phase (the periodic fold and ghost fill) over arrays named by NodeArray.
#pragma once
#include "kernels/dimension.hpp"
#include <array>
#include <initializer_list>
#include <vector>

#include "kernels/grid_update.hpp"
#include "kernels/views.hpp"

namespace SMPM_NS {

// The node arrays the halo phase takes by name. A vector name stands for its kDim arrays; an
// array the scene does not allocate is skipped.
enum class NodeArray {
  Mass, Momentum, Force, Velocity, VelocityChange, MassGradient, Volume, ContactHeat,
  // heat conduction (kernels/heat.hpp): C_i, S_i, T_i, dT_i
  HeatCapacity, HeatContent, Temperature, TemperatureChange
};

struct Grid {
  using Axes = std::array<std::vector<double>, kern::kDim>;
  kern::GridGeom geom;
  std::vector<double> m;
  Axes p, f, v, dv;                        // momentum, force, velocity, FLIP increment (FLIP only)
  Axes gm;                                 // mass gradient (several fields with normals)
  std::vector<double> vol, heat;           // volume, contact heat (several fields)
  std::vector<double> cap, capT, T, dT;    // heat conduction (Grid::enable_heat)
  int fields = 1;

  Grid() = default;
  // nfields > 1: several velocity fields (two-body contact or separated void faces), every array
  // holds one block per field; the mass gradients only with normals (two-body contact: a weld
  // of void faces needs none), the contact heat only where a gather reads it (two-body contact,
  // FLIP: the APIC weld's loss is the scatter loss, kern::weld_fields).
  Grid(const kern::GridGeom& g, bool flip, int nfields = 1, bool normals = true) : geom(g), fields(nfields) {
    const auto nn = g.num_nodes() * static_cast<std::size_t>(nfields) + kern::kLinePad;
    m.assign(nn, 0.0);
    for (int d = 0; d < kern::kDim; ++d) {
      for (auto* a : {&p[d], &f[d], &v[d]}) a->assign(nn, 0.0);
      if (flip) dv[d].assign(nn, 0.0);  // FLIP increments only where the transfer needs them
      if (nfields > 1 && normals) gm[d].assign(nn, 0.0);
    }
    if (nfields > 1) vol.assign(nn, 0.0);
    if (nfields > 1 && (normals || flip)) heat.assign(nn, 0.0);
  }
  // The arrays of grid heat conduction, one field.
  void enable_heat() {
    for (auto* a : {&cap, &capT, &T, &dT}) a->assign(geom.num_nodes(), 0.0);
  }
  kern::GridView view() {
    kern::GridView G{};
    G.m = m.data();
    for (int d = 0; d < kern::kDim; ++d) {
      G.p[d] = p[d].data();
      G.f[d] = f[d].data();
      G.v[d] = v[d].data();
      G.dv[d] = opt(dv[d]);
      G.gm[d] = opt(gm[d]);
    }
    G.vol = opt(vol);
    G.heat = opt(heat);
    G.fields = fields;
    G.fstride = fields > 1 ? geom.num_nodes() : 0;
    return G;
  }
  // The halo phase over the named arrays, every velocity field's block, inside box b: fold
  // after a scatter (ghost sums onto the nodes they stand for), fill after a grid update (ghosts
  // take the values of their nodes). A no-op without a periodic axis. This is the one place
  // where node values cross the grid's edges.
  void fold(const kern::NodeBox& b, std::initializer_list<NodeArray> names) {
    const auto a = arrays(names);
    kern::fold_periodic(geom, b, a.data(), static_cast<int>(a.size()));
  }
  void fill(const kern::NodeBox& b, std::initializer_list<NodeArray> names) {
    const auto a = arrays(names);
    kern::fill_periodic_ghosts(geom, b, a.data(), static_cast<int>(a.size()));
  }
  std::size_t bytes() const {
    std::size_t b = 0;
    for (const auto* a : {&m, &vol, &heat, &cap, &capT, &T, &dT}) b += a->capacity() * sizeof(double);
    for (int d = 0; d < kern::kDim; ++d)
      for (const auto* a : {&p[d], &f[d], &v[d], &dv[d], &gm[d]}) b += a->capacity() * sizeof(double);
    return b;
  }

 private:
  static double* opt(std::vector<double>& a) { return a.empty() ? nullptr : a.data(); }
  std::vector<std::vector<double>*> storage(NodeArray n) {
    std::vector<std::vector<double>*> s;
    const auto axes = [&](Axes& arr) {
      for (auto& a : arr) s.push_back(&a);
    };
    switch (n) {
      case NodeArray::Mass: s.push_back(&m); break;
      case NodeArray::Momentum: axes(p); break;
      case NodeArray::Force: axes(f); break;
      case NodeArray::Velocity: axes(v); break;
      case NodeArray::VelocityChange: axes(dv); break;
      case NodeArray::MassGradient: axes(gm); break;
      case NodeArray::Volume: s.push_back(&vol); break;
      case NodeArray::ContactHeat: s.push_back(&heat); break;
      case NodeArray::HeatCapacity: s.push_back(&cap); break;
      case NodeArray::HeatContent: s.push_back(&capT); break;
      case NodeArray::Temperature: s.push_back(&T); break;
      case NodeArray::TemperatureChange: s.push_back(&dT); break;
    }
    return s;
  }
  // every allocated array of the names, one pointer per velocity field's block
  std::vector<double*> arrays(std::initializer_list<NodeArray> names) {
    std::vector<double*> out;
    const std::size_t nn = geom.num_nodes();
    for (NodeArray n : names)
      for (auto* a : storage(n)) {
        if (a->empty()) continue;
        for (std::size_t k = 0; k < a->size() / nn; ++k) out.push_back(a->data() + k * nn);
      }
    return out;
  }
};

}  // namespace SMPM_NS
