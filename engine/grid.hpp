// Background grid storage: node arrays over the padded node range of kern::GridGeom.
#pragma once
#include <vector>

#include "kernels/views.hpp"

namespace smpm {

struct Grid {
  kern::GridGeom geom;
  std::vector<double> m, px, py, fx, fy, vx, vy, dvx, dvy;

  Grid() = default;
  Grid(const kern::GridGeom& g, bool flip) : geom(g) {
    const auto nn = g.num_nodes();
    for (auto* a : {&m, &px, &py, &fx, &fy, &vx, &vy}) a->assign(nn, 0.0);
    if (flip) {  // FLIP increments only where the transfer needs them
      dvx.assign(nn, 0.0);
      dvy.assign(nn, 0.0);
    }
  }
  kern::GridView view() {
    return {m.data(),  px.data(), py.data(), fx.data(), fy.data(), vx.data(), vy.data(),
            dvx.empty() ? nullptr : dvx.data(), dvy.empty() ? nullptr : dvy.data()};
  }
  std::size_t bytes() const {
    std::size_t b = 0;
    for (auto* a : {&m, &px, &py, &fx, &fy, &vx, &vy, &dvx, &dvy}) b += a->capacity() * sizeof(double);
    return b;
  }
};

}  // namespace smpm
