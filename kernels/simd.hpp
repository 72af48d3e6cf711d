// The fixed-width vectors of the 3D transfers (kern::gather_sums_by_line, kern::scatter_slots):
// a line of up to 4 nodes along axis 0 (Line), and 8 of a node's scatter values (Slots), as GCC
// vector types, which compile to the widest registers the processor has. madd is the one fused
// multiply-add the kernels ask for by name (-ffp-contract=off everywhere else): one rounding
// where the processor has FMA (x86 __FMA__, __AVX512F__), a multiply and an add otherwise. Either
// way each point's operations are fixed, so any thread count gives the same bits; processors
// with and without FMA differ in the last bits of the 3D transfers.
#pragma once
#include "dimension.hpp"

#include "tensor.hpp"

#if defined(__FMA__) || defined(__AVX512F__)
#include <immintrin.h>
#endif

namespace SMPM_NS::kern {

typedef double Line __attribute__((vector_size(4 * sizeof(double))));
typedef long long LineMask __attribute__((vector_size(4 * sizeof(long long))));
typedef double Slots __attribute__((vector_size(8 * sizeof(double))));

// The N nodes from a, as one 4-double load with the lanes past N cleared (the node arrays carry
// kLinePad doubles past their end, kernels/views.hpp).
template <int N>
SMPM_INLINE Line load_line(const double* a) {
  static_assert(N >= 1 && N <= 4, "a line holds 1 to 4 nodes");
  Line r;
  __builtin_memcpy(&r, a, sizeof r);
  if constexpr (N < 4) {
    constexpr LineMask keep = {-1, 1 < N ? -1 : 0, 2 < N ? -1 : 0, 0};
    r = reinterpret_cast<Line>(reinterpret_cast<LineMask>(r) & keep);
  }
  return r;
}

// (a_0 + a_1) + (a_2 + a_3)
SMPM_INLINE double lane_sum(Line a) { return (a[0] + a[1]) + (a[2] + a[3]); }

// a * b + c
SMPM_INLINE Line madd(Line a, Line b, Line c) {
#if defined(__FMA__)
  return _mm256_fmadd_pd(a, b, c);
#else
  return a * b + c;
#endif
}
SMPM_INLINE Line madd(double a, Line b, Line c) { return madd(Line{a, a, a, a}, b, c); }

SMPM_INLINE Slots madd(Slots a, Slots b, Slots c) {
#if defined(__AVX512F__)
  return _mm512_fmadd_pd(a, b, c);
#elif defined(__FMA__)
  Line a2[2], b2[2], c2[2];
  __builtin_memcpy(a2, &a, sizeof a);
  __builtin_memcpy(b2, &b, sizeof b);
  __builtin_memcpy(c2, &c, sizeof c);
  for (int h = 0; h < 2; ++h) c2[h] = madd(a2[h], b2[h], c2[h]);
  __builtin_memcpy(&c, c2, sizeof c);
  return c;
#else
  return a * b + c;
#endif
}
SMPM_INLINE Slots madd(double a, Slots b, Slots c) { return madd(Slots{a, a, a, a, a, a, a, a}, b, c); }

}  // namespace SMPM_NS::kern
