#include "sort.hpp"

#include <omp.h>

#include <algorithm>

namespace smpm::kern {

std::ptrdiff_t compute_keys(const GridGeom& g, const double* x, const double* y, std::size_t n,
                            std::uint32_t* key) {
  std::ptrdiff_t bad = static_cast<std::ptrdiff_t>(n);
#pragma omp parallel
  {
    // thread-local geometry and restrict pointers (through the shared ones GCC reloads them
    // per point)
    const KeyGeom gl(g);
    const double* __restrict xl = x;
    const double* __restrict yl = y;
    std::uint32_t* __restrict kl = key;
#pragma omp for simd schedule(static) reduction(min : bad)
    for (std::size_t i = 0; i < n; ++i) {
      std::uint32_t k;
      const bool inside = cell_key(gl, xl[i], yl[i], k);
      kl[i] = k;
      bad = std::min(bad, inside ? static_cast<std::ptrdiff_t>(n) : static_cast<std::ptrdiff_t>(i));
    }
  }
  return bad == static_cast<std::ptrdiff_t>(n) ? -1 : bad;
}

void counting_sort(const std::uint32_t* key, std::size_t n, std::size_t nkeys, std::uint32_t* hist,
                   std::uint32_t* cell_start, std::uint32_t* order) {
  constexpr int kMaxThreads = 1024;
  std::uint32_t block_total[kMaxThreads];
  const int nthreads = std::min(omp_get_max_threads(), kMaxThreads);
#pragma omp parallel num_threads(nthreads)
  {
    const int T = omp_get_num_threads();
    const int t = omp_get_thread_num();
    // contiguous particle chunk and key block of this thread
    const std::size_t i0 = n * t / T, i1 = n * (t + 1) / T;
    const std::size_t k0 = nkeys * t / T, k1 = nkeys * (t + 1) / T;
    std::uint32_t* h = hist + static_cast<std::size_t>(t) * nkeys;
    std::fill(h, h + nkeys, 0u);
    for (std::size_t i = i0; i < i1; ++i) ++h[key[i]];
#pragma omp barrier
    // totals per key for this thread's key block
    std::uint32_t block = 0;
    for (std::size_t k = k0; k < k1; ++k) {
      std::uint32_t c = 0;
      for (int u = 0; u < T; ++u) c += hist[static_cast<std::size_t>(u) * nkeys + k];
      cell_start[k] = c;
      block += c;
    }
    block_total[t] = block;
#pragma omp barrier
    std::uint32_t base = 0;  // exclusive scan of the block totals
    for (int u = 0; u < t; ++u) base += block_total[u];
    // turn counts into start offsets, and per-thread histograms into per-thread write cursors
    for (std::size_t k = k0; k < k1; ++k) {
      const std::uint32_t c = cell_start[k];
      cell_start[k] = base;
      std::uint32_t off = base;
      for (int u = 0; u < T; ++u) {
        std::uint32_t& hu = hist[static_cast<std::size_t>(u) * nkeys + k];
        const std::uint32_t cu = hu;
        hu = off;
        off += cu;
      }
      base += c;
    }
#pragma omp barrier
    for (std::size_t i = i0; i < i1; ++i) order[h[key[i]]++] = static_cast<std::uint32_t>(i);
#pragma omp single
    cell_start[nkeys] = static_cast<std::uint32_t>(n);
  }
}

}  // namespace smpm::kern
