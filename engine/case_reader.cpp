#include "engine/case_reader.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace smpm {

const Quantity kLength{"length", {{"m", 1.0}, {"mm", 1e-3}, {"um", 1e-6}}};
const Quantity kTime{"time", {{"s", 1.0}, {"us", 1e-6}, {"ns", 1e-9}}};
const Quantity kVelocity{"velocity", {{"m_s", 1.0}, {"km_s", 1e3}}};
const Quantity kStress{"stress", {{"Pa", 1.0}, {"MPa", 1e6}, {"GPa", 1e9}}};
const Quantity kDensity{"density", {{"kg_m3", 1.0}, {"g_cc", 1e3}}};
const Quantity kAcceleration{"acceleration", {{"m_s2", 1.0}}};
const Quantity kSpecificHeat{"specific heat", {{"J_kgK", 1.0}}};
const Quantity kConductivity{"thermal conductivity", {{"W_mK", 1.0}}};
const Quantity kTemperature{"temperature", {{"K", 1.0}}};
const Quantity kViscosity{"viscosity", {{"Pa_s", 1.0}}};
const Quantity kDimensionless{"number", {}};

namespace {
// the quantities with suffixes, for has() and stem()
const Quantity* const kSuffixed[] = {&kLength,       &kTime,         &kVelocity,       &kStress,     &kDensity,
                                     &kAcceleration, &kSpecificHeat, &kConductivity, &kTemperature, &kViscosity};
}  // namespace

std::string format_number(double v, int digits) {
  std::ostringstream s;
  s.precision(digits);
  s << v;
  return s.str();
}

namespace {

std::string fmt(double v) { return format_number(v, 10); }

std::string join(const std::vector<std::string>& v) {
  std::string r;
  for (std::size_t i = 0; i < v.size(); ++i) r += (i ? ", " : "") + ("'" + v[i] + "'");
  return r;
}

std::string where(const toml::node& n) {
  const auto& s = n.source();
  if (!s.begin) return "";
  return " (line " + std::to_string(s.begin.line) + ")";
}

// Edits (insert, delete, replace, swap of neighbours) from a to b, for "did you mean".
std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i)
    for (std::size_t j = 1; j <= b.size(); ++j) {
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (a[i - 1] != b[j - 1])});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[a.size()][b.size()];
}

// The candidate nearest to key, if near enough to be a typo of it (else empty).
std::string nearest(const std::string& key, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t bd = std::max<std::size_t>(2, key.size() / 4) + 1;
  for (const auto& c : candidates) {
    const std::size_t e = edit_distance(key, c);
    if (e < bd) {
      bd = e;
      best = c;
    }
  }
  return best;
}

// A value as written in the case file, for messages ("abc" with its quotes).
std::string shown(const toml::node& n) {
  std::ostringstream o;
  n.visit([&](const auto& v) { o << v; });  // a value, array or table as TOML writes it
  return o.str();
}

std::optional<double> as_number(const toml::node& n) {
  if (auto v = n.value<double>()) return *v;  // integers convert too
  return std::nullopt;
}

}  // namespace

const toml::table& CaseReader::empty() {
  static const toml::table t;
  return t;
}

CaseReader::CaseReader(const toml::table& table, std::string path, toml::table& resolved)
    : t_(&table), path_(std::move(path)), out_(&resolved) {}

void CaseReader::fail(const std::string& key, const std::string& msg) const {
  const std::string full = path_.empty() ? key : path_ + "." + key;
  const toml::node* n = t_->get(key);
  throw CaseError("case key '" + full + "'" + (n ? where(*n) : "") + ": " + msg);
}

void CaseReader::required(const std::vector<std::string>& spellings, const std::string& what) const {
  const std::string prefix = path_.empty() ? "" : path_ + ".";
  for (const auto& [k, v] : *t_) {
    const std::string key(k.str());
    if (std::find(used_.begin(), used_.end(), key) != used_.end()) continue;
    const std::string near = nearest(key, spellings);
    if (!near.empty())
      throw CaseError("unknown key '" + key + "' in " + (path_.empty() ? "the top level" : "[" + path_ + "]") +
                      where(v) + ": did you mean '" + near + "'? ('" + prefix + spellings.front() +
                      "' is required: " + what + ")");
  }
  throw CaseError("case key '" + prefix + spellings.front() + "' is required (" + what + ")");
}

const toml::node* CaseReader::find(const std::string& key) {
  const toml::node* n = t_->get(key);
  if (n) used_.push_back(key);
  return n;
}

bool CaseReader::has(const std::string& key) const {
  if (t_->get(key)) return true;
  for (const Quantity* q : kSuffixed)
    for (const auto& [suf, f] : q->suffixes)
      if (t_->get(key + "_" + suf)) return true;
  return false;
}

std::pair<std::string, double> CaseReader::find_quantity(const std::string& key, const Quantity& q) {
  if (q.suffixes.empty()) return {t_->get(key) ? key : "", 1.0};
  std::string found;
  double factor = 1.0;
  std::vector<std::string> names;
  for (const auto& [suf, f] : q.suffixes) {
    const std::string k = key + "_" + suf;
    names.push_back(k);
    if (t_->get(k)) {
      if (!found.empty()) fail(k, "given twice, also as '" + found + "'; keep one");
      found = k;
      factor = f;
    }
  }
  if (t_->get(key))
    fail(key, "a " + std::string(q.what) + " needs its unit in the key name: one of " + join(names));
  return {found, factor};
}

double CaseReader::quantity(const std::string& key, const Quantity& q, double lo, double hi) {
  auto [k, f] = find_quantity(key, q);
  if (k.empty()) {
    std::vector<std::string> names;
    for (const auto& [suf, ff] : q.suffixes) names.push_back(key + "_" + suf);
    if (names.empty()) names.push_back(key);
    required(names, "a " + std::string(q.what) + "; accepted spellings: " + join(names));
  }
  const toml::node* n = find(k);
  const auto v = as_number(*n);
  if (!v) fail(k, "expected a number, got " + shown(*n));
  const double si = *v * f;
  if (!std::isfinite(si) || si < lo || si > hi)
    fail(k, "value " + fmt(*v) + " is out of range: allowed " + fmt(lo / f) + " to " + fmt(hi / f));
  out_->insert_or_assign(k, *v);
  return si;
}

double CaseReader::quantity(const std::string& key, const Quantity& q, double lo, double hi, double def) {
  auto [k, f] = find_quantity(key, q);
  if (k.empty()) {
    const std::string canon = q.suffixes.empty() ? key : key + "_" + q.suffixes.front().first;
    out_->insert_or_assign(canon, def);
    return def;
  }
  return quantity(key, q, lo, hi);
}

namespace {
// "two numbers, e.g. [0, 1]", "3 numbers, e.g. [0, 1, 2]"
std::string count_example(std::size_t count) {
  std::string e = (count == 2 ? std::string("two") : std::to_string(count)) + " numbers, e.g. [";
  for (std::size_t i = 0; i < count; ++i) e += (i ? ", " : "") + std::to_string(i);
  return e + "]";
}
}  // namespace

std::vector<double> CaseReader::numbers(const std::string& key, const Quantity& q, std::size_t count) {
  auto [k, f] = find_quantity(key, q);
  if (k.empty()) {
    std::vector<std::string> names;
    for (const auto& [suf, ff] : q.suffixes) names.push_back(key + "_" + suf);
    if (names.empty()) names.push_back(key);
    required(names, count_example(count) + "; accepted spellings: " + join(names));
  }
  const toml::node* n = find(k);
  const toml::array* a = n->as_array();
  bool ok = a && a->size() == count;
  for (std::size_t i = 0; ok && i < count; ++i) ok = as_number(*a->get(i)).has_value();
  if (!ok) fail(k, "expected " + count_example(count) + ", got " + shown(*n));
  std::vector<double> v(count);
  toml::array r;
  for (std::size_t i = 0; i < count; ++i) {
    const double x = *as_number(*a->get(i));
    if (!std::isfinite(x)) fail(k, "values must be finite");
    r.push_back(x);
    v[i] = x * f;
  }
  out_->insert_or_assign(k, std::move(r));
  return v;
}

std::vector<double> CaseReader::numbers(const std::string& key, const Quantity& q, std::size_t count,
                                        const std::vector<double>& def_si) {
  auto [k, f] = find_quantity(key, q);
  if (k.empty()) {
    toml::array r;
    for (const double x : def_si) r.push_back(x);
    out_->insert_or_assign(q.suffixes.empty() ? key : key + "_" + q.suffixes.front().first, std::move(r));
    return def_si;
  }
  return numbers(key, q, count);
}

std::pair<double, double> CaseReader::pair(const std::string& key, const Quantity& q, bool increasing) {
  const std::vector<double> v = numbers(key, q, 2);
  if (increasing && !(v[0] < v[1])) {
    const auto [k, f] = find_quantity(key, q);
    fail(k, "[" + fmt(v[0] / f) + ", " + fmt(v[1] / f) + "]: the first value must be below the second");
  }
  return {v[0], v[1]};
}

std::pair<double, double> CaseReader::pair(const std::string& key, const Quantity& q, bool increasing,
                                           std::pair<double, double> def) {
  if (find_quantity(key, q).first.empty()) {
    const std::vector<double> v = numbers(key, q, 2, {def.first, def.second});
    return {v[0], v[1]};
  }
  return pair(key, q, increasing);
}

double CaseReader::number(const std::string& key, double lo, double hi) {
  const toml::node* n = find(key);
  if (!n) required({key}, "a number from " + fmt(lo) + " to " + fmt(hi));
  const auto v = as_number(*n);
  if (!v) fail(key, "expected a number, got " + shown(*n));
  if (!std::isfinite(*v) || *v < lo || *v > hi)
    fail(key, "value " + fmt(*v) + " is out of range: allowed " + fmt(lo) + " to " + fmt(hi));
  out_->insert_or_assign(key, *v);
  return *v;
}

double CaseReader::number(const std::string& key, double lo, double hi, double def) {
  if (!t_->get(key)) {
    out_->insert_or_assign(key, def);
    return def;
  }
  return number(key, lo, hi);
}

long CaseReader::integer(const std::string& key, long lo, long hi) {
  const toml::node* n = find(key);
  if (!n) required({key}, "a whole number from " + std::to_string(lo) + " to " + std::to_string(hi));
  const auto v = n->value_exact<int64_t>();
  if (!v) fail(key, "expected a whole number from " + std::to_string(lo) + " to " + std::to_string(hi) + ", got " + shown(*n));
  if (*v < lo || *v > hi)
    fail(key, "value " + std::to_string(*v) + " is out of range: allowed " + std::to_string(lo) + " to " + std::to_string(hi));
  out_->insert_or_assign(key, *v);
  return static_cast<long>(*v);
}

long CaseReader::integer(const std::string& key, long lo, long hi, long def) {
  if (!t_->get(key)) {
    out_->insert_or_assign(key, static_cast<int64_t>(def));
    return def;
  }
  return integer(key, lo, hi);
}

bool CaseReader::boolean(const std::string& key, bool def) {
  const toml::node* n = find(key);
  if (!n) {
    out_->insert_or_assign(key, def);
    return def;
  }
  const auto v = n->value_exact<bool>();
  if (!v) fail(key, "expected true or false, got " + shown(*n));
  out_->insert_or_assign(key, *v);
  return *v;
}

std::string CaseReader::string(const std::string& key) {
  const toml::node* n = find(key);
  if (!n) required({key}, "a string");
  const auto v = n->value_exact<std::string>();
  if (!v) fail(key, "expected a string in quotes, got " + shown(*n));
  out_->insert_or_assign(key, *v);
  return *v;
}

std::string CaseReader::string(const std::string& key, const std::string& def) {
  if (!t_->get(key)) {
    out_->insert_or_assign(key, def);
    return def;
  }
  return string(key);
}

std::string CaseReader::choice(const std::string& key, const std::vector<std::string>& allowed) {
  if (!t_->get(key)) required({key}, "one of " + join(allowed));
  const std::string v = string(key);
  if (std::find(allowed.begin(), allowed.end(), v) == allowed.end())
    fail(key, "'" + v + "' is not a valid choice: allowed " + join(allowed));
  return v;
}

std::string CaseReader::choice(const std::string& key, const std::vector<std::string>& allowed,
                               const std::string& def) {
  if (!t_->get(key)) {
    out_->insert_or_assign(key, def);
    return def;
  }
  return choice(key, allowed);
}

CaseReader CaseReader::table(const std::string& key) {
  const toml::node* n = find(key);
  if (n && !n->is_table()) fail(key, "expected a table ([" + key + "])");
  auto [it, ok] = out_->insert_or_assign(key, toml::table{});
  (void)ok;
  return CaseReader(n ? *n->as_table() : empty(), path_.empty() ? key : path_ + "." + key,
                    *it->second.as_table());
}

std::vector<CaseReader> CaseReader::tables(const std::string& key) {
  std::vector<CaseReader> r;
  const toml::node* n = find(key);
  if (!n) return r;
  const toml::array* a = n->as_array();
  if (!a || !a->is_array_of_tables()) fail(key, "expected an array of tables ([[" + key + "]])");
  auto [it, ok] = out_->insert_or_assign(key, toml::array{});
  (void)ok;
  toml::array* oa = it->second.as_array();
  for (std::size_t i = 0; i < a->size(); ++i) oa->push_back(toml::table{});
  for (std::size_t i = 0; i < a->size(); ++i)
    r.emplace_back(*a->get(i)->as_table(), (path_.empty() ? key : path_ + "." + key) + "[" + std::to_string(i) + "]",
                   *oa->get(i)->as_table());
  return r;
}

bool CaseReader::used(const std::string& key) const {
  return std::find(used_.begin(), used_.end(), key) != used_.end();
}

std::string CaseReader::stem(const std::string& key) {
  for (const Quantity* q : kSuffixed)
    for (const auto& [suf, f] : q->suffixes) {
      const std::string tail = std::string("_") + suf;
      if (key.size() > tail.size() && key.compare(key.size() - tail.size(), tail.size(), tail) == 0)
        return key.substr(0, key.size() - tail.size());
    }
  return key;
}

void CaseReader::finish() const {
  std::vector<std::string> unknown;
  for (const auto& [k, v] : *t_) {
    const std::string key(k.str());
    if (std::find(used_.begin(), used_.end(), key) == used_.end()) unknown.push_back(key);
  }
  if (unknown.empty()) return;
  std::vector<std::string> known = used_;
  for (const auto& [k, v] : *out_) known.push_back(std::string(k.str()));
  std::sort(known.begin(), known.end());
  known.erase(std::unique(known.begin(), known.end()), known.end());
  std::string hint;
  for (const auto& u : unknown) {
    const std::string near = nearest(u, known);
    if (!near.empty())
      hint += (hint.empty() ? "; did you mean " : ", ") + ("'" + near + "'") + (unknown.size() > 1 ? " for '" + u + "'" : "");
  }
  if (!hint.empty()) hint += "?";
  throw CaseError("unknown key" + std::string(unknown.size() > 1 ? "s " : " ") + join(unknown) + " in " +
                  (path_.empty() ? "the top level" : "[" + path_ + "]") + hint + "; the keys read here are " + join(known));
}

toml::table parse_case_file(const std::filesystem::path& file) {
  if (!std::filesystem::exists(file)) throw CaseError("case file '" + file.string() + "' does not exist");
  try {
    return toml::parse_file(file.string());
  } catch (const toml::parse_error& e) {
    std::ostringstream s;
    s << "case file '" << file.string() << "' line " << e.source().begin.line << ", column "
      << e.source().begin.column << ": " << e.description();
    throw CaseError(s.str());
  }
}

void apply_overrides(toml::table& t, const std::vector<std::string>& sets) {
  for (const auto& s : sets) {
    const auto eq = s.find('=');
    if (eq == std::string::npos || eq == 0)
      throw CaseError("--set '" + s + "': expected section.key=value (value in TOML syntax, strings quoted)");
    const std::string path = s.substr(0, eq);
    const std::string value = s.substr(eq + 1);
    toml::table parsed;
    try {
      parsed = toml::parse("v = " + value);
    } catch (const toml::parse_error& e) {
      throw CaseError("--set '" + s + "': value is not valid TOML (" + std::string(e.description()) +
                      "); quote strings, e.g. solver.scheme=\"musl\"");
    }
    toml::table* cur = &t;
    std::string rest = path;
    for (;;) {
      const auto dot = rest.find('.');
      if (dot == std::string::npos) break;
      const std::string part = rest.substr(0, dot);
      rest = rest.substr(dot + 1);
      toml::node* n = cur->get(part);
      if (!n) {
        cur->insert(part, toml::table{});
        n = cur->get(part);
      }
      if (n->is_array_of_tables()) {  // [[bodies]]: the next part names an entry, by index or name
        toml::array& arr = *n->as_array();
        const auto dot2 = rest.find('.');
        if (dot2 == std::string::npos)
          throw CaseError("--set '" + s + "': '" + part + "' is a list of tables: name an entry, as " + part +
                          ".0.key=value (by index) or " + part + ".NAME.key=value (by its name key)");
        const std::string sel = rest.substr(0, dot2);
        rest = rest.substr(dot2 + 1);
        std::string names;
        toml::table* found = nullptr;
        for (std::size_t k = 0; k < arr.size(); ++k) {
          toml::table* e = arr.get(k)->as_table();
          const std::string name = e->get_as<std::string>("name") ? e->get_as<std::string>("name")->get() : "";
          names += (names.empty() ? "" : ", ") + std::to_string(k) + (name.empty() ? "" : " (" + name + ")");
          if (sel == std::to_string(k) || (!name.empty() && sel == name)) found = e;
        }
        if (!found)
          throw CaseError("--set '" + s + "': '" + part + "' has no entry '" + sel + "'; its entries: " + names);
        cur = found;
        continue;
      }
      if (!n->is_table()) throw CaseError("--set '" + s + "': '" + part + "' is not a table");
      cur = n->as_table();
    }
    cur->insert_or_assign(rest, *parsed.get("v"));
  }
}

}  // namespace smpm
