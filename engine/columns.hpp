// The tables a run writes (series.csv, energy.csv, front.csv, wall.csv, voids.csv, gauges.csv,
// freesurface.csv), each described by one list of columns in file order: the CSV header, every
// row and the units (series.h5) come from that list.
#pragma once
#include <cstddef>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

namespace smpm {

// One column of a table whose rows are built as a `Row`. A number column has `value`; a text
// column (a region's, gauge's or body's name) has `text`, which the CSV writes in place of the
// number (`value`, where a text column has one too, is what series.h5 stores for it).
template <class Row>
struct Column {
  const char* name;                              // header entry, its unit in its suffix
  const char* unit;                              // the value's unit, in words
  double (*value)(const Row& r) = nullptr;       // the number written
  std::string_view (*text)(const Row& r) = nullptr;  // a text column's entry
};

// "a,b,c\n" from a column list's names.
template <class Columns>
std::string csv_header(const Columns& cols) {
  std::string h;
  for (const auto& c : cols) {
    if (!h.empty()) h += ',';
    h += c.name;
  }
  h += '\n';
  return h;
}

// One CSV row: the columns' entries for `r`, comma-separated, in the stream's number format.
template <class Columns, class Row>
void csv_row(std::ostream& o, const Columns& cols, const Row& r) {
  bool first = true;
  for (const auto& c : cols) {
    if (!first) o << ',';
    first = false;
    if (c.text) o << c.text(r);
    else o << c.value(r);
  }
  o << '\n';
}

// The columns' names and units, in file order.
template <class Columns>
std::vector<std::string> column_names(const Columns& cols) {
  std::vector<std::string> v;
  for (const auto& c : cols) v.emplace_back(c.name);
  return v;
}
template <class Columns>
std::vector<std::string> column_units(const Columns& cols) {
  std::vector<std::string> v;
  for (const auto& c : cols) v.emplace_back(c.unit);
  return v;
}

}  // namespace smpm
