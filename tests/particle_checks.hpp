// Test helper: compare particle arrays by the names the checkpoints use.
#pragma once
#include "kernels/dimension.hpp"
#include <catch2/catch.hpp>

#include <initializer_list>
#include <map>
#include <string>
#include <vector>

#include "engine/particles.hpp"

namespace SMPM_NS::test {

// The double arrays of P by name ("x", "vy", "sxy", "Lyx", "V", "p", ...: Particles::each_array).
inline std::map<std::string, const std::vector<double>*> arrays_by_name(const Particles& P) {
  std::map<std::string, const std::vector<double>*> a;
  const_cast<Particles&>(P).for_each_double([&](const FieldName& n, std::vector<double>& v) { a[n.str()] = &v; });
  return a;
}

// REQUIRE the named arrays of A and B equal, bit for bit.
inline void require_same(const Particles& A, const Particles& B, std::initializer_list<const char*> names) {
  const auto a = arrays_by_name(A), b = arrays_by_name(B);
  for (const char* n : names) {
    INFO("particle array " << n);
    REQUIRE(a.count(n) == 1);
    REQUIRE(b.count(n) == 1);
    REQUIRE(*a.at(n) == *b.at(n));
  }
}

}  // namespace SMPM_NS::test
