// Thread scaling of one scene, measured by interleaving: one process, one simulation, and
// rounds of K steps that alternate between thread counts (order A B, then B A, ...), so both
// thread counts see the same machine state and the same physical state of the run. On a shared
// machine whose speed drifts by 10-20 % over minutes, two separate runs (one per thread count)
// measure the drift as much as the scaling; interleaved rounds cancel it.
//
//   bench_scaling CASE [--set section.key=value ...] [--threads 1,2] [--rounds 10]
//                 [--steps-per-round 5] [--warmup 10] [--verify-steps 0]
//
// --verify-steps K: before the timing, one fresh simulation per thread count runs K steps from
// the initial state, and a hash of its particle state (every array, bitwise) is printed per
// thread count: the results must be identical for every count ("bitwise: identical" or
// "bitwise: DIFFER", exit 1).
//
// Prints, per phase and for the whole step, the median over rounds of the time per
// particle-step for each thread count, and the median over rounds of the per-round ratio
// (first thread count / each other). Results are bitwise identical across thread counts
// (the kernels are deterministic), so switching the count mid-run changes nothing physical.
//
// Each round also times a reference kernel right after the scene's steps, with the same thread
// count: independent, L1-resident, compute-only work (a chain of square roots and divisions per
// element, static schedule), the most a loop can gain from more threads on this machine at that
// moment. Its ratio is printed as "machine", and each phase's ratio divided by it as
// "of machine": a vCPU of a shared host does not always deliver a whole core. A second
// reference, a STREAM triad over 3 x 32 MiB (far beyond the L3), gives the memory system's own
// 2/1 in the same rounds ("memory"): what a memory-bound phase can gain at that moment. On a
// shared 2-vCPU VM it ranged from 1.1 to 1.9 between runs of bench/throughput.py (its
// triad), and a neighbour's traffic can lower it without touching the compute reference.
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <array>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "engine/case_reader.hpp"
#include "engine/scene.hpp"
#include "engine/simulation.hpp"

namespace {

using smpm::PhaseTimes;

constexpr int kPhases = 8;  // sort, p2g, grid, contact, g2p, constitutive, heat, step
const char* kPhaseName[kPhases] = {"sort", "p2g", "grid", "contact", "g2p", "constitutive", "heat", "step"};

std::array<double, kPhases> as_array(const PhaseTimes& t) {
  return {t.sort, t.p2g, t.grid, t.contact, t.g2p, t.constitutive, t.heat, t.total()};
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// The reference kernel: n elements of compute-only work split statically over the threads.
double reference_work(long n) {
  double s = 0.0;
#pragma omp parallel for schedule(static) reduction(+ : s)
  for (long i = 0; i < n; ++i) {
    double x = 1.0 + static_cast<double>(i & 1023) * 1e-3;
    for (int k = 0; k < 20; ++k) x = std::sqrt(x * 1.0001 + 0.5) / (1.0 + 1e-9 * x);
    s += x;
  }
  return s;
}

// The memory reference: a[i] = b[i] + 3 c[i] over 3 arrays of 32 MiB, static schedule (one
// memory domain on this machine, so where the arrays were first touched does not matter).
struct Triad {
  static constexpr long kN = 4L << 20;
  std::vector<double> a, b, c;
  Triad() : a(kN, 0.0), b(kN, 1.0), c(kN, 2.0) {}
  double run() {
    double* __restrict x = a.data();
    const double* __restrict y = b.data();
    const double* __restrict z = c.data();
#pragma omp parallel for schedule(static)
    for (long i = 0; i < kN; ++i) x[i] = y[i] + 3.0 * z[i];
    return x[kN / 2];
  }
};

[[noreturn]] void usage(const std::string& why) {
  std::fprintf(stderr,
               "error: %s\nusage: bench_scaling CASE [--set section.key=value ...] [--threads 1,2] "
               "[--rounds N>=1] [--steps-per-round K>=1] [--warmup W>=0] [--verify-steps K>=0]\n",
               why.c_str());
  std::exit(2);
}

long positive(const std::string& key, const std::string& v, long lo) {
  char* end = nullptr;
  const long x = std::strtol(v.c_str(), &end, 10);
  if (end == v.c_str() || *end != '\0' || x < lo)
    usage(key + " = '" + v + "': expected an integer >= " + std::to_string(lo));
  return x;
}

// FNV-1a over the bytes of every particle array: equal hashes, bitwise-equal state.
std::uint64_t state_hash(const smpm::Particles& P) {
  std::uint64_t h = 1469598103934665603ull;
  auto add = [&](const void* data, std::size_t bytes) {
    const auto* b = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < bytes; ++i) h = (h ^ b[i]) * 1099511628211ull;
  };
  std::vector<const std::vector<double>*> arrays;
  for (const auto& a : P.x) arrays.push_back(&a);
  for (const auto& a : P.v) arrays.push_back(&a);
  arrays.push_back(&P.V);
  for (const auto& a : P.s) arrays.push_back(&a);
  arrays.push_back(&P.p);
  for (const auto& a : P.C) arrays.push_back(&a);
  for (const auto* a : {&P.e, &P.epsp, &P.q}) arrays.push_back(a);
  for (const auto* a : arrays) add(a->data(), a->size() * sizeof(double));
  add(P.id.data(), P.id.size() * sizeof(P.id[0]));
  return h;
}

// One fresh simulation per thread count, `steps` steps each: prints each state's hash, true when
// all are equal.
bool same_state_for(const std::vector<int>& threads, const smpm::Scene& scene, long steps) {
  std::vector<std::uint64_t> hashes;
  for (int t : threads) {
    omp_set_num_threads(t);
    smpm::Simulation sim(scene.geom, scene.solver, scene.materials, scene.body_material, scene.particles);
    sim.store_gradient(false);
    for (long s = 0; s < steps; ++s) sim.step();
    hashes.push_back(state_hash(sim.particles()));
    std::printf("# state after %ld steps with %2d threads: %016llx\n", steps, t,
                static_cast<unsigned long long>(hashes.back()));
  }
  const bool same = std::all_of(hashes.begin(), hashes.end(), [&](auto x) { return x == hashes[0]; });
  std::printf("# bitwise: %s\n", same ? "identical" : "DIFFER");
  return same;
}

}  // namespace

int main(int argc, char** argv) {
  std::string case_file;
  std::vector<std::string> sets;
  std::vector<int> threads{1, 2};
  long rounds = 10, per_round = 5, warmup = 10, verify_steps = 0;
  for (int a = 1; a < argc; ++a) {
    const std::string s = argv[a];
    auto value = [&]() -> std::string {
      if (a + 1 >= argc) usage(s + " needs a value");
      return argv[++a];
    };
    if (s == "--set") sets.push_back(value());
    else if (s == "--rounds") rounds = positive(s, value(), 1);
    else if (s == "--steps-per-round") per_round = positive(s, value(), 1);
    else if (s == "--warmup") warmup = positive(s, value(), 0);
    else if (s == "--verify-steps") verify_steps = positive(s, value(), 0);
    else if (s == "--threads") {
      threads.clear();
      std::stringstream ss(value());
      for (std::string t; std::getline(ss, t, ',');) threads.push_back(static_cast<int>(positive("--threads", t, 1)));
      if (threads.size() < 2) usage("--threads needs at least two counts, e.g. 1,2");
    } else if (!s.empty() && s[0] == '-') usage("unknown option " + s);
    else if (case_file.empty()) case_file = s;
    else usage("more than one case file");
  }
  if (case_file.empty()) usage("no case file");

  try {
    auto doc = smpm::parse_case_file(case_file);
    smpm::apply_overrides(doc, sets);
    const std::filesystem::path path(case_file);
    smpm::Scene scene = smpm::build_scene(doc, path.stem().string(), path.parent_path());
    const int max_threads = *std::max_element(threads.begin(), threads.end());
    if (verify_steps > 0 && !same_state_for(threads, scene, verify_steps)) return 1;
    omp_set_num_threads(max_threads);  // the sort's per-thread histograms are sized at construction
    smpm::Simulation sim(scene.geom, scene.solver, scene.materials, scene.body_material,
                         std::move(scene.particles));
    const double n = static_cast<double>(sim.particles().size());
    sim.store_gradient(false);  // as in a run between its statistics (shockmpm run stores the gradient measures for those steps only)
    for (long s = 0; s < warmup; ++s) sim.step();
    const std::size_t T = threads.size();
    // per thread count, per phase: seconds of each round
    std::vector<std::array<std::vector<double>, kPhases>> sec(T);
    std::vector<std::vector<double>> ref_sec(T), mem_sec(T);
    Triad triad;
    constexpr long kRefWork = 400000;  // about 6 ms with one thread (the loop is vectorized)
    volatile double sink = 0.0;
    for (long r = 0; r < rounds; ++r) {
      for (std::size_t k = 0; k < T; ++k) {
        const std::size_t u = r % 2 ? T - 1 - k : k;  // A B, B A, A B, ...
        omp_set_num_threads(threads[u]);
        const auto before = as_array(sim.phase_times());
        for (long s = 0; s < per_round; ++s) sim.step();
        const auto after = as_array(sim.phase_times());
        for (int f = 0; f < kPhases; ++f) sec[u][f].push_back(after[f] - before[f]);
        const double t0 = omp_get_wtime();
        sink = sink + reference_work(kRefWork);
        ref_sec[u].push_back(omp_get_wtime() - t0);
        const double t1 = omp_get_wtime();
        sink = sink + triad.run();
        mem_sec[u].push_back(omp_get_wtime() - t1);
      }
    }
    const double ps = n * static_cast<double>(per_round);
    std::printf("# %s: %.0f particles, %ld warm-up steps, %ld rounds of %ld steps per thread count, "
                "t = %.4g ns at the end\n",
                case_file.c_str(), n, warmup, rounds, per_round, sim.time() * 1e9);
    std::printf("%-13s", "phase");
    for (int t : threads) std::printf("  ns/p-step %2d thr", t);
    for (std::size_t k = 1; k < T; ++k) std::printf("  %d/%d ratio (min-max)  of machine", threads[k], threads[0]);
    std::printf("\n");
    struct Spread {
      double median, lo, hi;
    };
    auto ratio = [](const std::vector<double>& a, const std::vector<double>& b) {  // per round a / b
      std::vector<double> r(a.size());
      for (std::size_t i = 0; i < a.size(); ++i) r[i] = a[i] / b[i];
      const auto [lo, hi] = std::minmax_element(r.begin(), r.end());
      return Spread{median(r), *lo, *hi};
    };
    std::vector<double> machine(T, 1.0);
    for (std::size_t k = 1; k < T; ++k) machine[k] = ratio(ref_sec[0], ref_sec[k]).median;
    for (int f = 0; f < kPhases; ++f) {
      if (median(sec[0][f]) <= 0.0) continue;  // phase not run in this scene
      std::printf("%-13s", kPhaseName[f]);
      for (std::size_t k = 0; k < T; ++k) std::printf("  %16.2f", median(sec[k][f]) / ps * 1e9);
      for (std::size_t k = 1; k < T; ++k) {
        const Spread r = ratio(sec[0][f], sec[k][f]);
        std::printf("  %8.3f (%.2f-%.2f)  %10.3f", r.median, r.lo, r.hi, r.median / machine[k]);
      }
      std::printf("\n");
    }
    auto reference_row = [&](const char* name, const std::vector<std::vector<double>>& t, const char* what) {
      std::printf("%-13s", name);
      for (std::size_t k = 0; k < T; ++k) std::printf("  %13.1f ms", median(t[k]) * 1e3);
      for (std::size_t k = 1; k < T; ++k) {
        const Spread r = ratio(t[0], t[k]);
        std::printf("  %8.3f (%.2f-%.2f)", r.median, r.lo, r.hi);
      }
      std::printf("   (%s)\n", what);
    };
    reference_row("machine", ref_sec, "reference kernel: compute-only, same thread counts, same rounds");
    reference_row("memory", mem_sec, "STREAM triad over 96 MiB, same thread counts, same rounds");
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
