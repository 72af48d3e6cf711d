// Reading case files (TOML). Every value is read through CaseReader, which
//  - converts units named by the key's suffix (cell_size_um = 5 -> 5e-6 m),
//  - checks ranges and choices, naming the key, the value and what is allowed,
//  - records each value it read, defaults included, into the resolved case (run.json),
//  - rejects keys nobody read (typos), listing the keys that are allowed.
#pragma once
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <toml++/toml.h>

namespace smpm {

// A number for a message, as a person reads it (%g style, `digits` significant digits).
std::string format_number(double v, int digits = 4);

struct CaseError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// A physical quantity: accepted key suffixes and their factors to SI.
struct Quantity {
  const char* what;  // "length", used in messages
  std::vector<std::pair<const char*, double>> suffixes;  // first = canonical SI suffix
};
extern const Quantity kLength, kTime, kVelocity, kStress, kDensity, kAcceleration, kSpecificHeat,
    kConductivity, kTemperature, kViscosity, kDimensionless;

class CaseReader {
 public:
  // `path` names the table in messages ("grid", "bodies[1]"); `resolved` receives what was read.
  CaseReader(const toml::table& table, std::string path, toml::table& resolved);

  bool has(const std::string& key) const;  // plain key or key with any suffix of any quantity
  // Quantity in SI units. Exactly one of key_<suffix> may be present.
  double quantity(const std::string& key, const Quantity& q, double lo, double hi);
  double quantity(const std::string& key, const Quantity& q, double lo, double hi, double def);
  // An array of `count` numbers in SI units, e.g. center_um = [10, 20, 30].
  std::vector<double> numbers(const std::string& key, const Quantity& q, std::size_t count);
  std::vector<double> numbers(const std::string& key, const Quantity& q, std::size_t count,
                              const std::vector<double>& def_si);
  // Two-element array, e.g. x_range_um = [0, 400]; requires first < second when `increasing`.
  std::pair<double, double> pair(const std::string& key, const Quantity& q, bool increasing);
  std::pair<double, double> pair(const std::string& key, const Quantity& q, bool increasing,
                                 std::pair<double, double> def_si);
  double number(const std::string& key, double lo, double hi);
  double number(const std::string& key, double lo, double hi, double def);
  long integer(const std::string& key, long lo, long hi);
  long integer(const std::string& key, long lo, long hi, long def);
  bool boolean(const std::string& key, bool def);
  std::string choice(const std::string& key, const std::vector<std::string>& allowed);
  std::string choice(const std::string& key, const std::vector<std::string>& allowed, const std::string& def);
  std::string string(const std::string& key);
  std::string string(const std::string& key, const std::string& def);
  // Sub-table (must be a table if present; an absent one reads as empty).
  CaseReader table(const std::string& key);
  // Array of tables, e.g. [[bodies]].
  std::vector<CaseReader> tables(const std::string& key);
  // Throws CaseError for keys present but never read.
  void finish() const;
  bool used(const std::string& key) const;  // was this exact key read?
  // The key without a unit suffix ("yield_stress_MPa" -> "yield_stress").
  static std::string stem(const std::string& key);
  const std::string& path() const { return path_; }

 private:
  const toml::node* find(const std::string& key);
  std::pair<std::string, double> find_quantity(const std::string& key, const Quantity& q);
  [[noreturn]] void fail(const std::string& key, const std::string& msg) const;
  // A required key is missing: a key of the table near one of its spellings (a typo) is named
  // as the unknown key it is, with the spelling meant; else "is required (what)".
  [[noreturn]] void required(const std::vector<std::string>& spellings, const std::string& what) const;
  static const toml::table& empty();

  const toml::table* t_;
  std::string path_;
  toml::table* out_;
  std::vector<std::string> used_;
  std::vector<toml::table*> child_out_;
};

// Parses a TOML file; errors name the file, line and column.
toml::table parse_case_file(const std::filesystem::path& file);
// Applies "section.key=value" overrides (value in TOML syntax); creates missing tables.
void apply_overrides(toml::table& t, const std::vector<std::string>& sets);

}  // namespace smpm
