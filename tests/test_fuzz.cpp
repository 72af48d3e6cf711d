// A mutation fuzzer over the case reader, the scene builder and the simulation's set-up.
// Seeds: the repo's case files. Each input is one seed with 1-3 random mutations
// (delete a key, rename it with a typo, give it a value of another type, a huge, tiny, zero,
// negative, NaN or infinite number, a wrong-sized array, a nested table). Every input must end
// in a built scene or a CaseError (exit 2 in the driver) within a second: any other exception,
// a crash or a hang fails. Sizes are capped (run.max_memory_gb = 0.5) so that no input
// allocates much.
//
// Deterministic: mutation k uses seed k, so a failure names the input that reproduces it.
// Bounded by time: SHOCKMPM_FUZZ_SECONDS (default 10) or SHOCKMPM_FUZZ_INPUTS, whichever ends
// first. With a libFuzzer or AFL++ build this would be a coverage-guided target; the Debian
// toolchain here (g++ 12) has neither, so this is a plain random mutator.
#include <catch2/catch.hpp>
#include <omp.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "engine/case_reader.hpp"
#include "engine/scene.hpp"
#include "engine/simulation.hpp"

using namespace smpm;

namespace {

struct Slot {  // a mutable place in the document: a table and one of its keys
  toml::table* table;
  std::string key;
  std::string path;
};

void collect(toml::table& t, const std::string& path, std::vector<Slot>& out) {
  for (auto&& [k, v] : t) {
    const std::string key(k.str());
    const std::string p = path.empty() ? key : path + "." + key;
    out.push_back({&t, key, p});
    if (auto* sub = v.as_table()) collect(*sub, p, out);
    if (auto* arr = v.as_array())
      for (std::size_t i = 0; i < arr->size(); ++i)
        if (auto* st = arr->get(i)->as_table()) collect(*st, p + "." + std::to_string(i), out);
  }
}

// One random value of any TOML type, sizes and signs chosen to hit range checks.
void random_value(std::mt19937_64& rng, toml::table& t, const std::string& key) {
  static const double numbers[] = {0.0, -1.0, 1e-300, 1e300, -1e300, 1e9, 1e-9, 3.5, 2.0, 7.0,
                                   std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
                                   -std::numeric_limits<double>::infinity(), 0.5, 255.0, 256.0, 1e6};
  switch (std::uniform_int_distribution<int>(0, 8)(rng)) {
    case 0: t.insert_or_assign(key, numbers[rng() % std::size(numbers)]); break;
    case 1: t.insert_or_assign(key, static_cast<int64_t>(std::uniform_int_distribution<int64_t>(-5, 1000000000)(rng))); break;
    case 2: t.insert_or_assign(key, std::string(rng() % 2 ? "cubic" : "")); break;
    case 3: t.insert_or_assign(key, bool(rng() % 2)); break;
    case 4: t.insert_or_assign(key, toml::array{numbers[rng() % std::size(numbers)]}); break;
    case 5: t.insert_or_assign(key, toml::array{numbers[rng() % std::size(numbers)], numbers[rng() % std::size(numbers)]}); break;
    case 6: t.insert_or_assign(key, toml::array{1.0, 2.0, 3.0}); break;
    case 7: t.insert_or_assign(key, toml::table{{"x", 1.0}}); break;
    default: t.insert_or_assign(key, toml::array{toml::table{{"name", "b"}}}); break;
  }
}

std::string mutate(std::mt19937_64& rng, toml::table& doc) {
  std::vector<Slot> slots;
  collect(doc, "", slots);
  if (slots.empty()) return "empty";
  const Slot s = slots[rng() % slots.size()];
  switch (std::uniform_int_distribution<int>(0, 3)(rng)) {
    case 0: s.table->erase(s.key); return "delete " + s.path;
    case 1: {  // typo: drop or double a character
      std::string k = s.key;
      const std::size_t i = rng() % k.size();
      if (rng() % 2) k.erase(i, 1);
      else k.insert(i, 1, k[i]);
      if (k.empty() || s.table->contains(k)) return "typo (none) " + s.path;
      if (auto* n = s.table->get(s.key)) {
        n->visit([&](const auto& v) { s.table->insert(k, v); });
        s.table->erase(s.key);
      }
      return "typo " + s.path + " -> " + k;
    }
    default: random_value(rng, *s.table, s.key); return "value " + s.path;
  }
}

}  // namespace

TEST_CASE("fuzz: mutated case files end in a scene or a CaseError, never anything else", "[case][fuzz]") {
  namespace fs = std::filesystem;
  const fs::path root = SHOCKMPM_SOURCE_DIR;
  std::vector<fs::path> seeds;
  for (const char* dir : {"cases", "cases/verify", "cases/paper"})
    for (const auto& f : fs::directory_iterator(root / dir))
      if (f.path().extension() == ".toml" && f.path().filename() != "materials.toml") seeds.push_back(f.path());
  std::sort(seeds.begin(), seeds.end());
  REQUIRE(seeds.size() >= 10);
  const char* sec = std::getenv("SHOCKMPM_FUZZ_SECONDS");
  const char* cnt = std::getenv("SHOCKMPM_FUZZ_INPUTS");
  const double budget = sec ? std::atof(sec) : 10.0;
  const long max_inputs = cnt ? std::atol(cnt) : std::numeric_limits<long>::max();
  const auto t0 = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
  long inputs = 0, built = 0, rejected = 0, named = 0;
  std::vector<std::string> unnamed;  // rejections whose message names no key (first few)
  double slowest = 0.0;
  std::string slowest_what;
  for (long k = 0; k < max_inputs && elapsed() < budget; ++k) {
    std::mt19937_64 rng(static_cast<std::uint64_t>(k));
    const fs::path& seed = seeds[static_cast<std::size_t>(k) % seeds.size()];
    toml::table doc = parse_case_file(seed);
    std::string what = seed.filename().string();
    const int n = 1 + static_cast<int>(rng() % 3);
    for (int m = 0; m < n; ++m) what += "; " + mutate(rng, doc);
    // the size cap, whatever the mutation did to [run]
    if (auto* run = doc["run"].as_table()) run->insert_or_assign("max_memory_gb", 0.5);
    const double t1 = elapsed();
    INFO("input " << k << ": " << what);
    try {
      Scene sc = build_scene(doc, "fuzz", seed.parent_path());
      Simulation sim(sc.geom, sc.solver, sc.materials, sc.body_material, sc.particles);
      (void)sim.stable_dt();
      ++built;
    } catch (const CaseError& e) {
      ++rejected;
      const std::string m = e.what();
      const bool names_key = m.find("case key") != std::string::npos || m.find("unknown key") != std::string::npos ||
                             m.find("case table") != std::string::npos || m.find("case array") != std::string::npos ||
                             m.find("case body") != std::string::npos;
      if (names_key) ++named;
      else if (unnamed.size() < 5) unnamed.push_back(m);
    } catch (const std::exception& e) {
      FAIL_CHECK("not a CaseError: " << e.what());
    }
    ++inputs;
    if (elapsed() - t1 > slowest) {
      slowest = elapsed() - t1;
      slowest_what = what;
    }
  }
  WARN(inputs << " inputs in " << elapsed() << " s: " << built << " built, " << rejected << " rejected; slowest "
              << slowest << " s (" << slowest_what << ")");
  for (const auto& m : unnamed) WARN("rejected without naming a key: " << m);
  WARN(named << " of " << rejected << " rejections name the key");
  CHECK(inputs > 0);
  CHECK(named == rejected);  // every rejection names the key (or table) it is about
  CHECK(slowest < 5.0);  // no input may hang: the slowest seed (cases/paper, 742 k points) builds in ~1 s
}
