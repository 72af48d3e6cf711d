#include "dimension.hpp"
#include "sort.hpp"

#include <omp.h>

#include <algorithm>
#include <utility>

namespace SMPM_NS::kern {

namespace {

// The least and the greatest of key[i0..i1) (~0 and 0 when empty). A function of its own: written
// inside the parallel region, GCC ran this loop one key at a time.
std::pair<std::uint32_t, std::uint32_t> key_range(const std::uint32_t* key, std::size_t i0, std::size_t i1) {
  std::uint32_t kmin = ~0u, kmax = 0;
  for (std::size_t i = i0; i < i1; ++i) {
    kmin = std::min(kmin, key[i]);
    kmax = std::max(kmax, key[i]);
  }
  return {kmin, kmax};
}

// The counting sort's passes over a thread's points, run by run of equal keys: nearly sorted,
// the points of a cell come one after another (4 in a row at 2 x 2 points per cell), and
// incrementing the histogram entry point by point made each add wait for the one before
// through memory. count_runs adds each run's length to h[key]; place_runs writes the run's
// points at the cursor h[key] onward and advances it, as the point-by-point loops did.
void count_runs(const std::uint32_t* key, std::size_t i0, std::size_t i1, std::uint32_t* h) {
  std::size_t i = i0;
  while (i < i1) {
    const std::uint32_t k = key[i];
    std::size_t j = i + 1;
    while (j < i1 && key[j] == k) ++j;
    h[k] += static_cast<std::uint32_t>(j - i);
    i = j;
  }
}
void place_runs(const std::uint32_t* key, std::size_t i0, std::size_t i1, std::uint32_t* h, std::uint32_t* order) {
  std::size_t i = i0;
  while (i < i1) {
    const std::uint32_t k = key[i];
    std::uint32_t c = h[k];
    std::size_t j = i;
    for (; j < i1 && key[j] == k; ++j) order[c++] = static_cast<std::uint32_t>(j);
    h[k] = c;
    i = j;
  }
}

// Thread t's block [k0, k1) of the nkeys keys for the passes over keys: an equal share of their
// work, one unit per key and one more per thread whose histogram range [lo[u], hi[u]) holds it
// (an equal count of keys left the thread whose block held the points' keys waiting at the
// next barrier). The blocks cover the keys once, in thread order, whatever the ranges.
std::pair<std::size_t, std::size_t> key_block(const std::size_t* lo, const std::size_t* hi, int T, int t,
                                              std::size_t nkeys) {
  const auto work = [&](std::size_t k) {  // the work of keys [0, k)
    std::uint64_t w = k;
    for (int u = 0; u < T; ++u)
      if (hi[u] > lo[u] && k > lo[u]) w += std::min(k, hi[u]) - lo[u];
    return w;
  };
  const std::uint64_t total = work(nkeys);
  const auto start = [&](int p) {  // the first key k with work(k) >= total p / T
    if (p <= 0) return std::size_t{0};
    if (p >= T) return nkeys;
    const std::uint64_t target = total * static_cast<std::uint64_t>(p) / static_cast<std::uint64_t>(T);
    std::size_t a = 0, b = nkeys;
    while (a < b) {
      const std::size_t mid = a + (b - a) / 2;
      if (work(mid) < target) a = mid + 1;
      else b = mid;
    }
    return a;
  };
  return {start(t), start(t + 1)};
}

}  // namespace

// Binning in one parallel region (each region wakes the threads that sleep between regions):
// the keys (vectorized, with the first point outside the grid), then each thread counts its
// contiguous chunk of particles into its own histogram, over the key range [lo, hi) its chunk
// touches. The particles are nearly sorted (the engine permutes them into key
// order every few steps), so the ranges barely overlap and the histogram work (zeroing, the
// scan, the offsets) is split among the threads instead of each thread paying for all nkeys
// keys, which on a grid with many empty cells (the elastic block: 0.8 keys per particle) kept
// the sort from scaling with threads. In any order the result is the same; only the ranges grow.
std::ptrdiff_t sort_by_cell(const GridGeom& g, const double* const* pos, std::size_t n, std::uint32_t* key,
                            std::uint32_t* hist, std::uint32_t* cell_start, std::uint32_t* order) {
  constexpr int kMaxThreads = 1024;
  std::uint32_t block_total[kMaxThreads];
  std::size_t lo[kMaxThreads], hi[kMaxThreads];
  const std::size_t nkeys = g.num_keys();
  const int nthreads = std::min(omp_get_max_threads(), kMaxThreads);
  std::ptrdiff_t first_bad = static_cast<std::ptrdiff_t>(n);
#pragma omp parallel num_threads(nthreads)
  {
    const int T = omp_get_num_threads();
    const int t = omp_get_thread_num();
    // contiguous particle chunk and key block of this thread
    const auto [i0, i1] = thread_share(n);
    {
      // thread-local geometry and pointers (through the shared ones GCC reloads them per point)
      const KeyGeom gl(g);
      const double* __restrict pl[kDim];
      for (int d = 0; d < kDim; ++d) pl[d] = pos[d];
      std::uint32_t* __restrict kl = key;
#pragma omp for simd schedule(static) reduction(min : first_bad)
      for (std::size_t i = 0; i < n; ++i) {
        Vec<kDim> pt;
#pragma GCC unroll 3
        for (int d = 0; d < kDim; ++d) pt[d] = pl[d][i];
        const CellKey k = cell_key(gl, pt);
        kl[i] = k.key;
        first_bad = std::min(first_bad, k.inside ? static_cast<std::ptrdiff_t>(n) : static_cast<std::ptrdiff_t>(i));
      }
    }
    const auto [kmin, kmax] = key_range(key, i0, i1);
    lo[t] = i1 > i0 ? kmin : 0;
    hi[t] = i1 > i0 ? kmax + std::size_t{1} : 0;
    std::uint32_t* h = hist + static_cast<std::size_t>(t) * nkeys;
    std::fill(h + lo[t], h + hi[t], 0u);
    count_runs(key, i0, i1, h);
    if (first_bad == static_cast<std::ptrdiff_t>(n)) {  // read after the keys' barrier: all agree
#pragma omp barrier
      const auto [k0, k1] = key_block(lo, hi, T, t, nkeys);
      // the points of this thread's key block
      std::uint32_t block = 0;
      for (int u = 0; u < T; ++u) {
        const std::uint32_t* hu = hist + static_cast<std::size_t>(u) * nkeys;
        for (std::size_t k = std::max(k0, lo[u]); k < std::min(k1, hi[u]); ++k) block += hu[k];
      }
      block_total[t] = block;
#pragma omp barrier
      std::uint32_t base = 0;  // exclusive scan of the block totals
      for (int u = 0; u < t; ++u) base += block_total[u];
      // the threads whose key range meets this key block, in thread order: a few, since the
      // particles are nearly sorted (testing all T threads for every key made this loop cost
      // nkeys tests per thread whatever the thread count, and the sort 5x at 16 threads)
      int meets[kMaxThreads];
      int nmeet = 0;
      for (int u = 0; u < T; ++u)
        if (lo[u] < k1 && hi[u] > k0) meets[nmeet++] = u;
      // turn counts into start offsets, and per-thread histograms into per-thread write cursors:
      // cell_start[k] the points of keys below k, thread u's cursor that plus the points of key
      // k of the threads before u. Segment by segment between the ranges' ends, each with a fixed
      // set of threads whose range holds it: none (most keys of a sparse grid) or one (most
      // others, nearly sorted points) take a loop of their own.
      std::size_t a = k0;
      while (a < k1) {
        std::size_t b = k1;
        int held[kMaxThreads];
        int nheld = 0;
        for (int j = 0; j < nmeet; ++j) {
          const int u = meets[j];
          if (lo[u] > a) b = std::min(b, lo[u]);
          else if (hi[u] > a) {
            b = std::min(b, hi[u]);
            held[nheld++] = u;
          }
        }
        if (nheld == 0) {
          std::fill(cell_start + a, cell_start + b, base);
        } else if (nheld == 1) {
          std::uint32_t* hu = hist + static_cast<std::size_t>(held[0]) * nkeys;
          for (std::size_t k = a; k < b; ++k) {
            const std::uint32_t c = hu[k];
            cell_start[k] = base;
            hu[k] = base;
            base += c;
          }
        } else {
          for (std::size_t k = a; k < b; ++k) {
            cell_start[k] = base;
            for (int j = 0; j < nheld; ++j) {
              std::uint32_t& hu = hist[static_cast<std::size_t>(held[j]) * nkeys + k];
              const std::uint32_t cu = hu;
              hu = base;
              base += cu;
            }
          }
        }
        a = b;
      }
#pragma omp barrier
      place_runs(key, i0, i1, h, order);
      if (t == T - 1) cell_start[nkeys] = static_cast<std::uint32_t>(n);
    }
  }
  return first_bad == static_cast<std::ptrdiff_t>(n) ? -1 : first_bad;
}

}  // namespace SMPM_NS::kern
