// Scoped wall-clock timer: adds the seconds of its scope to an accumulator.
#pragma once
#include <omp.h>

namespace smpm {

struct Timed {
  double& acc;
  double t0 = omp_get_wtime();
  explicit Timed(double& a) : acc(a) {}
  ~Timed() { acc += omp_get_wtime() - t0; }
};

}  // namespace smpm
