#include "engine/particles.hpp"

#include <utility>

#include "kernels/sort.hpp"

namespace smpm {

namespace {
// Every double array in use: the optional ones only when allocated.
template <class F>
void for_each_double(Particles& P, F&& f) {
  for (auto* v : {&P.x, &P.y, &P.vx, &P.vy, &P.m, &P.V, &P.sxx, &P.syy, &P.sxy, &P.p, &P.Lxx, &P.Lxy,
                  &P.Lyx, &P.Lyy})
    f(*v);
  for (auto* v : {&P.Cxx, &P.Cxy, &P.Cyx, &P.Cyy, &P.e, &P.epsp, &P.q, &P.wp})
    if (!v->empty()) f(*v);
}
}  // namespace

void Particles::resize(std::size_t n) {
  for_each_double(*this, [n](std::vector<double>& v) { v.resize(n, 0.0); });
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
  for (auto* v : {&Cxx, &Cxy, &Cyx, &Cyy}) {
    if (on) v->assign(size(), 0.0);
    else std::vector<double>().swap(*v);
  }
}

kern::ParticleView Particles::view() {
  auto d = [](std::vector<double>& v) { return v.empty() ? nullptr : v.data(); };
  return {x.data(), y.data(), vx.data(), vy.data(), m.data(), V.data(), sxx.data(), syy.data(), sxy.data(),
          p.data(), Lxx.data(), Lxy.data(), Lyx.data(), Lyy.data(), d(Cxx), d(Cxy), d(Cyx), d(Cyy), d(q), d(e)};
}

void Particles::permute(const std::uint32_t* order, std::vector<double>& sd, std::vector<std::uint32_t>& su,
                        std::vector<std::uint8_t>& sb) {
  const std::size_t n = size();
  sd.resize(n);
  su.resize(n);
  sb.resize(n);
  for_each_double(*this, [&](std::vector<double>& v) {
    kern::gather_permute(v.data(), order, n, sd.data());
    v.swap(sd);
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
  for_each_double(const_cast<Particles&>(*this), [&](std::vector<double>& v) { b += v.capacity() * sizeof(double); });
  return b + id.capacity() * sizeof(std::uint32_t) + body.capacity() + field.capacity();
}

std::vector<std::string> Particles::fields_in_use() const {
  std::vector<std::string> names;
  const_cast<Particles&>(*this).each_array([&](const char* name, const auto&) { names.emplace_back(name); });
  return names;
}

void Particles::append(const Particles& o) {
  auto cat = [](auto& a, const auto& b) { a.insert(a.end(), b.begin(), b.end()); };
  cat(x, o.x); cat(y, o.y); cat(vx, o.vx); cat(vy, o.vy); cat(m, o.m); cat(V, o.V);
  cat(sxx, o.sxx); cat(syy, o.syy); cat(sxy, o.sxy); cat(p, o.p);
  cat(Lxx, o.Lxx); cat(Lxy, o.Lxy); cat(Lyx, o.Lyx); cat(Lyy, o.Lyy);
  cat(Cxx, o.Cxx); cat(Cxy, o.Cxy); cat(Cyx, o.Cyx); cat(Cyy, o.Cyy);
  cat(e, o.e); cat(epsp, o.epsp); cat(q, o.q); cat(wp, o.wp);
  cat(id, o.id); cat(body, o.body);
  if (!field.empty() || !o.field.empty()) {  // a side without fields is all field 0
    field.resize(size() - o.size(), 0);
    o.field.empty() ? field.resize(size(), 0) : cat(field, o.field);
  }
}

}  // namespace smpm
