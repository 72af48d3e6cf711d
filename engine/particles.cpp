#include "kernels/dimension.hpp"
#include "engine/particles.hpp"

#include <utility>

#include "kernels/sort.hpp"

namespace SMPM_NS {

void Particles::resize(std::size_t n) {
  for_each_double([n](const FieldName&, std::vector<double>& a) { a.resize(n, 0.0); });
  id.resize(n, 0);
  body.resize(n, 0);
  if (!field.empty()) field.resize(n, 0);
}

void Particles::enable(std::vector<double>& field, std::size_t n, bool on) {
  if (on) {
    if (field.size() != n) field.assign(n, 0.0);
  } else {
    std::vector<double>().swap(field);
  }
}

void Particles::enable_affine(bool on) {
  for (auto& a : C) {
    if (on) a.assign(size(), 0.0);
    else std::vector<double>().swap(a);
  }
}

kern::ParticleView Particles::view() {
  auto d = [](std::vector<double>& v) { return v.empty() ? nullptr : v.data(); };
  kern::ParticleView w{};
  for (int a = 0; a < kern::kDim; ++a) {
    w.x[a] = x[a].data();
    w.v[a] = v[a].data();
  }
  w.m = m.data();
  w.V = V.data();
  for (int k = 0; k < kSym; ++k) w.s[k] = s[k].data();
  w.p = p.data();
  for (int k = 0; k < kern::kDim * kern::kDim; ++k) w.C[k] = d(C[k]);
  w.q = d(q);
  w.e = d(e);
  return w;
}

void Particles::permute(const std::uint32_t* order, std::vector<double>& sd, std::vector<std::uint32_t>& su,
                        std::vector<std::uint8_t>& sb) {
  const std::size_t n = size();
  sd.resize(n);
  su.resize(n);
  sb.resize(n);
  for_each_double([&](const FieldName&, std::vector<double>& a) {
    kern::gather_permute(a.data(), order, n, sd.data());
    a.swap(sd);
  });
  kern::gather_permute(id.data(), order, n, su.data());
  id.swap(su);
  kern::gather_permute(body.data(), order, n, sb.data());
  body.swap(sb);
  if (!field.empty()) {
    kern::gather_permute(field.data(), order, n, sb.data());
    field.swap(sb);
  }
}

std::size_t Particles::bytes() const {
  std::size_t b = 0;
  const_cast<Particles&>(*this).for_each_double(
      [&](const FieldName&, std::vector<double>& a) { b += a.capacity() * sizeof(double); });
  return b + id.capacity() * sizeof(std::uint32_t) + body.capacity() + field.capacity();
}

std::vector<std::string> Particles::fields_in_use() const {
  std::vector<std::string> names;
  const_cast<Particles&>(*this).each_array([&](const char* name, const auto&) { names.emplace_back(name); });
  return names;
}

void Particles::append(const Particles& o) {
  auto cat = [](auto& a, const auto& b) { a.insert(a.end(), b.begin(), b.end()); };
  for (int d = 0; d < kern::kDim; ++d) {
    cat(x[d], o.x[d]);
    cat(v[d], o.v[d]);
  }
  cat(m, o.m); cat(V, o.V);
  for (int k = 0; k < kSym; ++k) cat(s[k], o.s[k]);
  cat(p, o.p);
  cat(curl2, o.curl2); cat(div, o.div); cat(rate2, o.rate2);
  for (int k = 0; k < kern::kDim * kern::kDim; ++k) cat(C[k], o.C[k]);
  cat(e, o.e); cat(epsp, o.epsp); cat(q, o.q); cat(wp, o.wp);
  cat(id, o.id); cat(body, o.body);
  if (!field.empty() || !o.field.empty()) {  // a side without fields is all field 0
    field.resize(size() - o.size(), 0);
    o.field.empty() ? field.resize(size(), 0) : cat(field, o.field);
  }
}

}  // namespace SMPM_NS
