// The colored MLS-MPM yardstick: a plain, scalar, double-precision 2D MLS-MPM (Hu et al. 2018,
// "A moving least squares material point method": quadratic B-splines, APIC's affine matrix C,
// the stress folded into the affine momentum) with the usual shared-memory race handling of a
// colored scatter, on the scene of cases/bench/elastic_block.toml. It shares no code with the
// engine: it is the reference that shows what the engine's tuning buys over a straightforward
// implementation on the same machine (docs/performance.md, "The MLS yardstick").
//
//   bench_mls [grid.cell_size_m=H] [run.max_steps=N] [--threads 1,2] [--rounds R] [--check]
//
// What it does per step (every loop over particles or nodes under `omp for`):
//   1. bin: each point's tile (8 x 8 cells of its stencil's first node); a counting sort of the
//      point indices by tile (per-thread histograms over static chunks); every 20 steps the
//      particle arrays are permuted into that order (as the engine's solver.permute_every).
//   2. clear the grid (mass, momentum).
//   3. P2G, colored: the tiles of one color (tile parity along x and y) are 16 cells apart and
//      their 3 x 3 stencils touch disjoint nodes, so the threads add straight into the grid
//      with plain adds, a dynamic schedule over the tiles of one color, the 4 colors in turn.
//      Per point: B-spline weights, the Cauchy stress of a small-strain linear elastic law from
//      F (sigma = lambda tr(eps) I + 2 mu eps, eps = sym(F) - I) at the volume V0 det F, the
//      affine momentum A = m C - dt V (4 / h^2) sigma, and for each of the 9 nodes
//      m_i += w m, (m v)_i += w (m v + A (x_i - x_p)).
//   4. grid update: v_i = (m v)_i / m_i + dt g; within 2 nodes of a wall the velocity into it
//      is zeroed (slip walls on all four sides).
//   5. G2P: v_p = sum w v_i, C_p = (4 / h^2) sum w v_i (x_i - x_p)^T, x_p += dt v_p,
//      F_p = (I + dt C_p) F_p.
// dt = 0.2 h / (c_p + 5 m/s), c_p the plane-strain P-wave speed, as in the bench case.
//
// Prints, per thread count, the median over rounds of M particle-steps/s (the steps alone,
// the setup excluded), of each phase's ns per particle-step and a hash of the final state (positions, velocities; must be the same
// for every thread count: the colored scatter's sums run in a fixed order). --check also
// compares the P2G's grid mass and momentum with the particles' (to 1e-9 relative, the round-off
// of sums over 1e6 points; MLS-MPM's scatter conserves both exactly), checks that every point
// ends finite and inside the domain, and exits 1 on a mismatch or differing hashes.
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace {

constexpr int kTile = 8;           // cells per tile and axis
constexpr int kPermuteEvery = 20;  // steps between permutations of the particle arrays

struct Scene {  // cases/bench/elastic_block.toml
  double h = 0.0008, Lx = 1.0, Ly = 0.5;
  double x0 = 0.3, x1 = 0.7, y0 = 0.0016, y1 = 0.4016, vy0 = -5.0, g = -9.81;
  double rho = 1000.0, E = 1.0e6, nu = 0.3, cfl = 0.2;
};

// Structure of arrays, the 12 arrays and the permutation's spare in one allocation, each starting
// 576 bytes further into a 4 KiB page than the one before (13 distinct offsets). Arrays that start
// at one offset in a page, which 8 MB std::vectors do (each its own page-aligned mmap), make the
// G2P's loads and stores of a point alias in the processor's 4 KiB address check: it ran at 46
// instead of 20 ns per particle-step on one thread, 2.3x, whenever the allocator happened to map
// them so (docs/performance.md, "The MLS yardstick").
struct Particles {
  static constexpr int kArrays = 12;
  std::size_t n = 0;
  std::vector<double> store;
  double* arr[kArrays + 1] = {};
  double *&x = arr[0], *&y = arr[1], *&vx = arr[2], *&vy = arr[3], *&C00 = arr[4], *&C01 = arr[5],
         *&C10 = arr[6], *&C11 = arr[7], *&F00 = arr[8], *&F01 = arr[9], *&F10 = arr[10], *&F11 = arr[11];
  double m = 0.0, V0 = 0.0;
  Particles() = default;
  Particles(const Particles&) = delete;
  Particles& operator=(const Particles&) = delete;
  std::size_t size() const { return n; }
  void allocate(std::size_t count) {
    n = count;
    const std::size_t stride = (n + 511) / 512 * 512 + 72;  // whole 4 KiB pages plus 576 bytes
    store.assign(stride * (kArrays + 1) + 8, 0.0);
    const std::size_t lead = (64 - reinterpret_cast<std::uintptr_t>(store.data()) % 64) % 64 / sizeof(double);
    for (int k = 0; k <= kArrays; ++k) arr[k] = store.data() + lead + k * stride;
  }
};

struct Sim {
  Scene s;
  Particles P;
  int nx = 0, ny = 0, tx = 0, ty = 0;  // nodes per axis, tiles per axis
  double inv_h = 0.0, dt = 0.0, lambda = 0.0, mu = 0.0;
  std::vector<double> gm, gvx, gvy;    // node mass, momentum then velocity
  std::vector<std::uint32_t> tile, order, start, hist;
  long steps = 0;

  explicit Sim(const Scene& sc) : s(sc) {
    inv_h = 1.0 / s.h;
    const int cx = static_cast<int>(std::lround(s.Lx / s.h)), cy = static_cast<int>(std::lround(s.Ly / s.h));
    nx = cx + 1;
    ny = cy + 1;
    tx = (nx + kTile - 1) / kTile;
    ty = (ny + kTile - 1) / kTile;
    gm.assign(std::size_t(nx) * ny, 0.0);
    gvx = gvy = gm;
    lambda = s.E * s.nu / ((1 + s.nu) * (1 - 2 * s.nu));
    mu = s.E / (2 * (1 + s.nu));
    const double c = std::sqrt((lambda + 2 * mu) / s.rho);
    dt = s.cfl * s.h / (c - s.vy0);
    // 2 x 2 points per cell, row by row
    const double d = 0.5 * s.h;
    std::vector<double> xs, ys;
    for (double y = s.y0 + 0.5 * d; y < s.y1; y += d)
      for (double x = s.x0 + 0.5 * d; x < s.x1; x += d) {
        xs.push_back(x);
        ys.push_back(y);
      }
    const std::size_t n = xs.size();
    P.allocate(n);  // zeros
    std::copy(xs.begin(), xs.end(), P.x);
    std::copy(ys.begin(), ys.end(), P.y);
    std::fill(P.vy, P.vy + n, s.vy0);
    std::fill(P.F00, P.F00 + n, 1.0);
    std::fill(P.F11, P.F11 + n, 1.0);
    P.V0 = d * d;
    P.m = s.rho * P.V0;
    tile.resize(n);
    order.resize(n);
    start.resize(std::size_t(tx) * ty + 1);
    hist.resize(std::size_t(omp_get_max_threads()) * tx * ty);
  }

  int base(double x) const { return static_cast<int>(x * inv_h - 0.5); }

  // 1. tiles and a counting sort of the indices by tile
  void bin() {
    const std::size_t n = P.size();
    const std::size_t nt = std::size_t(tx) * ty;
#pragma omp parallel
    {
      const int T = omp_get_num_threads(), t = omp_get_thread_num();
      std::uint32_t* hc = &hist[std::size_t(t) * nt];
      std::fill(hc, hc + nt, 0u);
      const std::size_t lo = n * t / T, hi = n * (t + 1) / T;
      for (std::size_t p = lo; p < hi; ++p) {
        const std::uint32_t k = std::uint32_t(base(P.y[p]) / kTile) * tx + std::uint32_t(base(P.x[p]) / kTile);
        tile[p] = k;
        ++hc[k];
      }
#pragma omp barrier
#pragma omp single
      {
        std::uint32_t sum = 0;
        for (std::size_t k = 0; k < nt; ++k) {
          start[k] = sum;
          for (int u = 0; u < T; ++u) {
            const std::uint32_t c = hist[std::size_t(u) * nt + k];
            hist[std::size_t(u) * nt + k] = sum;
            sum += c;
          }
        }
        start[nt] = sum;
      }
      for (std::size_t p = lo; p < hi; ++p) order[hc[tile[p]]++] = static_cast<std::uint32_t>(p);
    }
    if (steps % kPermuteEvery == 0) {
      for (int k = 0; k < Particles::kArrays; ++k) {
        const double* in = P.arr[k];
        double* out = P.arr[Particles::kArrays];
#pragma omp parallel for schedule(static)
        for (std::size_t i = 0; i < n; ++i) out[i] = in[order[i]];
        std::swap(P.arr[k], P.arr[Particles::kArrays]);
      }
#pragma omp parallel for schedule(static)
      for (std::size_t i = 0; i < n; ++i) order[i] = static_cast<std::uint32_t>(i);
    }
  }

  // point p's first node (bx, by), its position from that node in cells (fx, fy), the quadratic
  // B-spline weights of the 3 nodes along each axis
  void stencil(std::size_t p, int& bx, int& by, double& fx, double& fy, double wx[3], double wy[3]) const {
    bx = base(P.x[p]);
    by = base(P.y[p]);
    fx = P.x[p] * inv_h - bx;
    fy = P.y[p] * inv_h - by;
    for (int a = 0; a < 2; ++a) {
      const double f = a ? fy : fx;
      double* w = a ? wy : wx;
      w[0] = 0.5 * (1.5 - f) * (1.5 - f);
      w[1] = 0.75 - (f - 1.0) * (f - 1.0);
      w[2] = 0.5 * (f - 0.5) * (f - 0.5);
    }
  }

  // 2. and 3.
  void p2g() {
    const std::size_t nn = gm.size();
    const double Dinv = 4.0 * inv_h * inv_h;
#pragma omp parallel
    {
#pragma omp for schedule(static)
      for (std::size_t i = 0; i < nn; ++i) gm[i] = gvx[i] = gvy[i] = 0.0;
      for (int color = 0; color < 4; ++color) {
        const int cx = color & 1, cy = color >> 1;
        const int ntx = (tx - cx + 1) / 2, nty = (ty - cy + 1) / 2;
#pragma omp for schedule(dynamic, 1)
        for (int k = 0; k < ntx * nty; ++k) {
          const std::size_t t = std::size_t(2 * (k / ntx) + cy) * tx + std::size_t(2 * (k % ntx) + cx);
          for (std::uint32_t s0 = start[t]; s0 < start[t + 1]; ++s0) {
            const std::uint32_t p = order[s0];
            int bx, by;
            double fx, fy, wx[3], wy[3];
            stencil(p, bx, by, fx, fy, wx, wy);
            const double F00 = P.F00[p], F01 = P.F01[p], F10 = P.F10[p], F11 = P.F11[p];
            const double J = F00 * F11 - F01 * F10;
            const double e00 = F00 - 1.0, e11 = F11 - 1.0, e01 = 0.5 * (F01 + F10);
            const double tr = lambda * (e00 + e11);
            const double ks = -dt * P.V0 * J * Dinv;
            const double m = P.m;
            const double A00 = ks * (tr + 2 * mu * e00) + m * P.C00[p], A01 = ks * 2 * mu * e01 + m * P.C01[p];
            const double A10 = ks * 2 * mu * e01 + m * P.C10[p], A11 = ks * (tr + 2 * mu * e11) + m * P.C11[p];
            const double mvx = m * P.vx[p], mvy = m * P.vy[p];
            for (int j = 0; j < 3; ++j)
              for (int i = 0; i < 3; ++i) {
                const double w = wx[i] * wy[j];
                const double dx = (i - fx) * s.h, dy = (j - fy) * s.h;
                const std::size_t node = std::size_t(by + j) * nx + std::size_t(bx + i);
                gm[node] += w * m;
                gvx[node] += w * (mvx + A00 * dx + A01 * dy);
                gvy[node] += w * (mvy + A10 * dx + A11 * dy);
              }
          }
        }
      }
    }
  }

  // 4.
  void grid_update() {
#pragma omp parallel for schedule(static)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const std::size_t node = std::size_t(j) * nx + i;
        const double m = gm[node];
        if (m <= 0.0) continue;
        double vx = gvx[node] / m, vy = gvy[node] / m + dt * s.g;
        if ((i < 2 && vx < 0) || (i > nx - 3 && vx > 0)) vx = 0.0;
        if ((j < 2 && vy < 0) || (j > ny - 3 && vy > 0)) vy = 0.0;
        gvx[node] = vx;
        gvy[node] = vy;
      }
  }

  // 5.
  void g2p() {
    const std::size_t n = P.size();
    const double Dinv = 4.0 * inv_h * inv_h;
#pragma omp parallel for schedule(static)
    for (std::size_t p = 0; p < n; ++p) {
      int bx, by;
      double fx, fy, wx[3], wy[3];
      stencil(p, bx, by, fx, fy, wx, wy);
      double vx = 0, vy = 0, c00 = 0, c01 = 0, c10 = 0, c11 = 0;
      for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i) {
          const double w = wx[i] * wy[j];
          const double dx = (i - fx) * s.h, dy = (j - fy) * s.h;
          const std::size_t node = std::size_t(by + j) * nx + std::size_t(bx + i);
          const double ux = gvx[node], uy = gvy[node];
          vx += w * ux;
          vy += w * uy;
          c00 += w * ux * dx;
          c01 += w * ux * dy;
          c10 += w * uy * dx;
          c11 += w * uy * dy;
        }
      c00 *= Dinv;
      c01 *= Dinv;
      c10 *= Dinv;
      c11 *= Dinv;
      P.vx[p] = vx;
      P.vy[p] = vy;
      P.C00[p] = c00;
      P.C01[p] = c01;
      P.C10[p] = c10;
      P.C11[p] = c11;
      P.x[p] += dt * vx;
      P.y[p] += dt * vy;
      const double F00 = P.F00[p], F01 = P.F01[p], F10 = P.F10[p], F11 = P.F11[p];
      P.F00[p] = F00 + dt * (c00 * F00 + c01 * F10);
      P.F01[p] = F01 + dt * (c00 * F01 + c01 * F11);
      P.F10[p] = F10 + dt * (c10 * F00 + c11 * F10);
      P.F11[p] = F11 + dt * (c10 * F01 + c11 * F11);
    }
  }

  double seconds[4] = {};  // bin, p2g (with the clear), grid, g2p

  void step() {
    double t = omp_get_wtime();
    const auto lap = [&](int k) {
      const double now = omp_get_wtime();
      seconds[k] += now - t;
      t = now;
    };
    bin();
    lap(0);
    p2g();
    lap(1);
    grid_update();
    lap(2);
    g2p();
    lap(3);
    ++steps;
  }

  // the P2G's grid mass and momentum against the particles' (relative difference, the largest)
  double conservation_error() {
    bin();
    p2g();
    double m = 0, px = 0, py = 0, Gm = 0, Gx = 0, Gy = 0;
    for (std::size_t p = 0; p < P.size(); ++p) {
      m += P.m;
      px += P.m * P.vx[p];
      py += P.m * P.vy[p];
    }
    for (std::size_t i = 0; i < gm.size(); ++i) {
      Gm += gm[i];
      Gx += gvx[i];
      Gy += gvy[i];
    }
    const double scale = std::abs(py) + std::abs(px);
    return std::max({std::abs(Gm - m) / m, std::abs(Gx - px) / scale, std::abs(Gy - py) / scale});
  }

  bool inside() const {
    for (std::size_t p = 0; p < P.size(); ++p)
      if (!(P.x[p] >= 0.0 && P.x[p] <= s.Lx && P.y[p] >= 0.0 && P.y[p] <= s.Ly)) return false;
    return true;
  }

  std::uint64_t hash() const {
    std::uint64_t h = 1469598103934665603ull;
    for (const double* a : {P.x, P.y, P.vx, P.vy})
      for (std::size_t p = 0; p < P.size(); ++p) {
        std::uint64_t u;
        std::memcpy(&u, &a[p], 8);
        h = (h ^ u) * 1099511628211ull;
      }
    return h;
  }
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t k = v.size();
  return k % 2 ? v[k / 2] : 0.5 * (v[k / 2 - 1] + v[k / 2]);
}

[[noreturn]] void usage(const std::string& why) {
  std::fprintf(stderr,
               "bench_mls: %s\nusage: bench_mls [grid.cell_size_m=H] [run.max_steps=N] [--threads 1,2] "
               "[--rounds R] [--check]\n",
               why.c_str());
  std::exit(2);
}

}  // namespace

int main(int argc, char** argv) {
  Scene sc;
  long steps = 100;
  int rounds = 3;
  bool check = false;
  std::vector<int> threads{omp_get_max_threads()};
  for (int a = 1; a < argc; ++a) {
    const std::string s = argv[a];
    const auto value = [&](const std::string& key) { return s.substr(key.size()); };
    if (s.rfind("grid.cell_size_m=", 0) == 0) {
      sc.h = std::atof(value("grid.cell_size_m=").c_str());
      if (!(sc.h >= 2e-4 && sc.h <= 0.02)) usage("grid.cell_size_m = " + value("grid.cell_size_m=") + ": allowed 2e-4 to 0.02 [m]");
    } else if (s.rfind("run.max_steps=", 0) == 0) {
      steps = std::atol(value("run.max_steps=").c_str());
      if (steps < 1 || steps > 100000) usage("run.max_steps = " + value("run.max_steps=") + ": allowed 1 to 100000");
    } else if (s == "--threads" && a + 1 < argc) {
      threads.clear();
      std::string list = argv[++a];
      for (std::size_t p = 0; p < list.size();) {
        const std::size_t q = std::min(list.find(',', p), list.size());
        const int t = std::atoi(list.substr(p, q - p).c_str());
        if (t < 1 || t > 1024) usage("--threads " + list + ": each count 1 to 1024");
        threads.push_back(t);
        p = q + 1;
      }
    } else if (s == "--rounds" && a + 1 < argc) {
      rounds = std::atoi(argv[++a]);
      if (rounds < 1 || rounds > 1000) usage("--rounds " + std::string(argv[a]) + ": allowed 1 to 1000");
    } else if (s == "--check") {
      check = true;
    } else {
      usage("unknown argument '" + s + "'");
    }
  }
  int status = 0;
  std::vector<std::uint64_t> hashes;
  for (int t : threads) {
    omp_set_num_threads(t);
    std::vector<double> rate, phase[4];
    std::uint64_t h = 0;
    std::size_t n = 0;
    for (int r = 0; r < rounds; ++r) {
      Sim sim(sc);
      n = sim.P.size();
      if (check && r == 0) {
        const double err = sim.conservation_error();
        std::printf("threads %d: P2G mass and momentum against the particles': %.2e relative\n", t, err);
        if (!(err < 1e-9)) status = 1;  // the round-off of summing 1e6 terms in two orders: n eps = 1e-10
      }
      const double t0 = omp_get_wtime();
      for (long k = 0; k < steps; ++k) sim.step();
      rate.push_back(double(n) * double(steps) / (omp_get_wtime() - t0) * 1e-6);
      for (int k = 0; k < 4; ++k) phase[k].push_back(sim.seconds[k] / (double(n) * double(steps)) * 1e9);
      h = sim.hash();
      if (check && r == 0 && !sim.inside()) {
        std::printf("threads %d: a point ended outside the domain or not finite\n", t);
        status = 1;
      }
    }
    hashes.push_back(h);
    std::printf("threads %d: %zu particles, %ld steps, %.3f M particle-steps/s (median of %d), state hash %016llx\n", t,
                n, steps, median(rate), rounds, static_cast<unsigned long long>(h));
    std::printf("threads %d: ns per particle-step: bin %.2f, p2g %.2f, grid %.2f, g2p %.2f (medians)\n", t,
                median(phase[0]), median(phase[1]), median(phase[2]), median(phase[3]));
  }
  for (std::uint64_t h : hashes)
    if (h != hashes.front()) {
      std::printf("state hashes DIFFER between thread counts\n");
      status = 1;
    }
  return status;
}
