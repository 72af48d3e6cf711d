// The machine's two roofs, measured the same way every time, for bench/throughput.py:
//   memory bandwidth: a STREAM-like triad a[i] = b[i] + s c[i] over three arrays of 2^25
//     doubles (768 MiB in all, far past the caches), first-touch initialised by the threads
//     that use them; bytes counted as STREAM does (24 per element, write-allocate not counted);
//   double-precision FMA throughput: 16 independent FMA chains per thread on registers.
// Best of 10 repetitions each. Prints one JSON object:
//   {"threads": T, "triad_GB_s": ..., "fma_GFLOP_s": ...}
#include <omp.h>

#include <algorithm>
#include <cstdio>
#include <memory>

namespace {

double triad_GB_s() {
  const long n = 1L << 25;
  std::unique_ptr<double[]> a(new double[n]), b(new double[n]), c(new double[n]);
#pragma omp parallel for schedule(static)
  for (long i = 0; i < n; ++i) {
    a[i] = 0.0;
    b[i] = 1.0;
    c[i] = 2.0;
  }
  double best = 1e30;
  for (int rep = 0; rep < 10; ++rep) {
    const double s = 0.5 + rep;
    const double t0 = omp_get_wtime();
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; ++i) a[i] = b[i] + s * c[i];
    best = std::min(best, omp_get_wtime() - t0);
  }
  volatile double sink = a[n / 3];
  (void)sink;
  return 24.0 * double(n) / best * 1e-9;
}

double fma_GFLOP_s() {
  constexpr int kChains = 16, kWidth = 4;  // 16 chains of 4-wide vectors per thread
  const long iters = 20000000;
  double best = 1e30;
  double total = 0.0;
  for (int rep = 0; rep < 10; ++rep) {
    const double t0 = omp_get_wtime();
#pragma omp parallel reduction(+ : total)
    {
      double acc[kChains][kWidth];
      for (int c = 0; c < kChains; ++c)
        for (int w = 0; w < kWidth; ++w) acc[c][w] = 1.0 + 1e-3 * (c * kWidth + w + omp_get_thread_num());
      const double m = 0.999999, k = 1e-7;
      for (long i = 0; i < iters / 16; ++i)
#pragma GCC unroll 16
        for (int c = 0; c < kChains; ++c)
#pragma omp simd
          for (int w = 0; w < kWidth; ++w) acc[c][w] = acc[c][w] * m + k;
      double s = 0.0;
      for (int c = 0; c < kChains; ++c)
        for (int w = 0; w < kWidth; ++w) s += acc[c][w];
      total += s;
    }
    best = std::min(best, omp_get_wtime() - t0);
  }
  volatile double sink = total;
  (void)sink;
  const double flops = 2.0 * kChains * kWidth * double(iters / 16) * omp_get_max_threads();
  return flops / best * 1e-9;
}

}  // namespace

int main() {
  const double bw = triad_GB_s();
  const double fl = fma_GFLOP_s();
  std::printf("{\"threads\": %d, \"triad_GB_s\": %.2f, \"fma_GFLOP_s\": %.2f}\n", omp_get_max_threads(), bw, fl);
  return 0;
}
