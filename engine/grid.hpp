// Background grid storage: node arrays over the padded node range of kern::GridGeom.
#pragma once
#include <vector>

#include "kernels/views.hpp"

namespace smpm {

struct Grid {
  kern::GridGeom geom;
  std::vector<double> m, px, py, fx, fy, vx, vy, dvx, dvy;

  std::vector<double> gmx, gmy, vol, heat;  // several fields: mass gradient, volume, contact heat
  int fields = 1;

  Grid() = default;
  // nfields > 1: several velocity fields (two-body contact or separated void faces), every array
  // holds one block per field; the mass gradients only with normals (two-body contact: a weld
  // of void faces needs none).
  Grid(const kern::GridGeom& g, bool flip, int nfields = 1, bool normals = true) : geom(g), fields(nfields) {
    const auto nn = g.num_nodes() * static_cast<std::size_t>(nfields);
    for (auto* a : {&m, &px, &py, &fx, &fy, &vx, &vy}) a->assign(nn, 0.0);
    if (flip) {  // FLIP increments only where the transfer needs them
      dvx.assign(nn, 0.0);
      dvy.assign(nn, 0.0);
    }
    if (nfields > 1)
      for (auto* a : {&vol, &heat}) a->assign(nn, 0.0);
    if (nfields > 1 && normals)
      for (auto* a : {&gmx, &gmy}) a->assign(nn, 0.0);
  }
  kern::GridView view() {
    auto d = [](std::vector<double>& v) { return v.empty() ? nullptr : v.data(); };
    kern::GridView G{m.data(), px.data(), py.data(), fx.data(), fy.data(), vx.data(), vy.data(), d(dvx), d(dvy)};
    G.gmx = d(gmx);
    G.gmy = d(gmy);
    G.vol = d(vol);
    G.heat = d(heat);
    G.fields = fields;
    G.fstride = fields > 1 ? geom.num_nodes() : 0;
    return G;
  }
  std::size_t bytes() const {
    std::size_t b = 0;
    for (auto* a : {&m, &px, &py, &fx, &fy, &vx, &vy, &dvx, &dvy, &gmx, &gmy, &vol, &heat}) b += a->capacity() * sizeof(double);
    return b;
  }
};

}  // namespace smpm
